"""Reports of the speed/accuracy suite: results.json, results.csv, RESULTS.md and pareto.png.

The Pareto plot is drawn into a pixel buffer and written as a PNG with zlib (standard library
only): one panel per model, x = CPU time per primary ray (ns, log scale), y = mean hit-point error
relative to the model's diagonal (log scale), one color per surface, the Pareto front (no other
run both faster and more accurate) joined by a line.
"""
import csv
import json
import math
import os
import struct
import zlib

COLUMNS = ["model", "points", "surface", "setting", "prep_seconds", "prep_peak_mb", "bytes_per_point",
           "rays_per_s", "ns_per_ray", "hit_error_mean", "hit_error_p99", "hit_error_max", "hole_rate",
           "false_hit_rate", "normal_error_deg", "image_rmse", "image_psnr_db", "hit_fraction", "threads"]

SURFACE_COLORS = {"splats": (220, 60, 40), "iso": (40, 140, 60), "mls": (40, 80, 220), "patches": (160, 60, 180)}


def count_label(n):
    if n >= 1_000_000 and n % 1_000_000 == 0:
        return "%dM" % (n // 1_000_000)
    if n >= 1000 and n % 1000 == 0:
        return "%dk" % (n // 1000)
    return str(n)


def fmt(v, digits=3):
    if v is None:
        return "-"
    if isinstance(v, float):
        if v == 0:
            return "0"
        if abs(v) >= 1e4 or abs(v) < 1e-2:
            return "%.*e" % (digits - 1, v)
        return "%.*g" % (digits, v)
    return str(v)


def pareto_front(points):
    """Indices of the (x, y) points no other point beats in both (smaller is better)."""
    order = sorted(range(len(points)), key=lambda i: (points[i][0], points[i][1]))
    front, best = [], math.inf
    for i in order:
        if points[i][1] < best:
            front.append(i)
            best = points[i][1]
    return front


# ---- a tiny raster: 3x5 font, lines, PNG ------------------------------------------------------

FONT = {  # 3 columns x 5 rows, one string of 15 bits per glyph, row-major
    "0": "111101101101111", "1": "010110010010111", "2": "111001111100111", "3": "111001111001111",
    "4": "101101111001001", "5": "111100111001111", "6": "111100111101111", "7": "111001010010010",
    "8": "111101111101111", "9": "111101111001111", ".": "000000000000010", "-": "000000111000000",
    "+": "000010111010000", "e": "000111101110111", "a": "000011101101011", "b": "100110101101110",
    "c": "000111100100111", "d": "001011101101011", "f": "011100110100100", "g": "111101111001110",
    "h": "100110101101101", "i": "010000010010010", "k": "100101110101101", "l": "110010010010111",
    "m": "000111111101101", "n": "000110101101101", "o": "000111101101111", "p": "000111101111100",
    "r": "000110101100100", "s": "000011110001110", "t": "010111010010011", "u": "000101101101111",
    "v": "000101101101010", "w": "000101101111111", "x": "000101010101101", "y": "000101111001110",
    "z": "000111011110111", "_": "000000000000111", " ": "000000000000000", "/": "001001010100100",
    "(": "010100100100010", ")": "010001001001010", ",": "000000000010100", "=": "000111000111000",
    "%": "101001010100101", ":": "000010000010000", "q": "000111101111001", "j": "001000001001110",
}


class Canvas:
    def __init__(self, w, h):
        self.w, self.h = w, h
        self.px = bytearray([255] * (w * h * 3))

    def dot(self, x, y, c):
        if 0 <= x < self.w and 0 <= y < self.h:
            i = 3 * (y * self.w + x)
            self.px[i:i + 3] = bytes(c)

    def rect(self, x0, y0, x1, y1, c):
        for y in range(max(0, y0), min(self.h, y1 + 1)):
            for x in range(max(0, x0), min(self.w, x1 + 1)):
                self.dot(x, y, c)

    def line(self, x0, y0, x1, y1, c):
        n = max(abs(x1 - x0), abs(y1 - y0), 1)
        for k in range(n + 1):
            self.dot(round(x0 + (x1 - x0) * k / n), round(y0 + (y1 - y0) * k / n), c)

    def text(self, x, y, s, c=(0, 0, 0), scale=2):
        for ch in s.lower():
            g = FONT.get(ch, FONT[" "])
            for r in range(5):
                for col in range(3):
                    if g[r * 3 + col] == "1":
                        self.rect(x + col * scale, y + r * scale, x + col * scale + scale - 1,
                                  y + r * scale + scale - 1, c)
            x += 4 * scale

    def png(self, path):
        raw = b"".join(b"\x00" + bytes(self.px[3 * y * self.w:3 * (y + 1) * self.w]) for y in range(self.h))

        def chunk(kind, data):
            return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

        data = (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", self.w, self.h, 8, 2, 0, 0, 0)) +
                chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))
        tmp = path + ".tmp"
        with open(tmp, "wb") as f:
            f.write(data)
        os.replace(tmp, path)


def plot_pareto(rows, path, ykey="hit_error_mean",
                title="cpu time per ray (ns, log) against mean hit error / diagonal (log)"):
    models = []
    for r in rows:
        if r.get(ykey) and r.get("ns_per_ray") and r["model"] not in models:
            models.append(r["model"])
    pw, ph, margin = 360, 300, 60
    cols = min(3, max(1, len(models)))
    nrows = max(1, (len(models) + cols - 1) // cols)
    cv = Canvas(cols * (pw + margin) + margin, nrows * (ph + margin) + margin + 30)
    cv.text(margin, 8, title, scale=2)
    lx = margin
    for s, c in SURFACE_COLORS.items():
        cv.rect(lx, 26, lx + 8, 34, c)
        cv.text(lx + 12, 26, s, scale=2)
        lx += 40 + 8 * len(s)
    for m_i, model in enumerate(models):
        pts = [r for r in rows if r["model"] == model and r.get(ykey) and r.get("ns_per_ray")]
        x0 = margin + (m_i % cols) * (pw + margin)
        y0 = margin + 20 + (m_i // cols) * (ph + margin)
        xs = [math.log10(r["ns_per_ray"]) for r in pts]
        ys = [math.log10(r[ykey]) for r in pts]
        xa, xb = math.floor(min(xs)), math.ceil(max(xs))
        ya, yb = math.floor(min(ys)), math.ceil(max(ys))
        xb, yb = max(xb, xa + 1), max(yb, ya + 1)
        px = lambda v: x0 + int((v - xa) / (xb - xa) * (pw - 1))  # noqa: E731
        py = lambda v: y0 + ph - 1 - int((v - ya) / (yb - ya) * (ph - 1))  # noqa: E731
        cv.line(x0, y0 + ph, x0 + pw, y0 + ph, (0, 0, 0))
        cv.line(x0, y0, x0, y0 + ph, (0, 0, 0))
        for e in range(xa, xb + 1):
            cv.line(px(e), y0 + ph, px(e), y0 + ph + 4, (0, 0, 0))
            cv.text(px(e) - 6, y0 + ph + 8, "1e%d" % e, scale=1)
            cv.line(px(e), y0, px(e), y0 + ph - 1, (225, 225, 225))
        for e in range(ya, yb + 1):
            cv.line(x0 - 4, py(e), x0, py(e), (0, 0, 0))
            cv.text(x0 - 30, py(e) - 2, "1e%d" % e, scale=1)
            cv.line(x0 + 1, py(e), x0 + pw, py(e), (225, 225, 225))
        cv.text(x0, y0 - 14, model, scale=2)
        front = pareto_front(list(zip(xs, ys)))
        for a, b in zip(front, front[1:]):
            cv.line(px(xs[a]), py(ys[a]), px(xs[b]), py(ys[b]), (120, 120, 120))
        for r, x, y in zip(pts, xs, ys):
            c = SURFACE_COLORS.get(r["surface"], (0, 0, 0))
            cv.rect(px(x) - 2, py(y) - 2, px(x) + 2, py(y) + 2, c)
    cv.png(path)


def markdown(result):
    meta, rows = result["meta"], result["runs"]
    out = ["# PointRT speed/accuracy suite", "",
           "Generated by `scripts/suite/run.sh%s%s OUT_DIR` (%s, git %s, host %s with %s CPUs, %.0f s). "
           "Errors are relative to the model's bounding-box diagonal; hit error = distance of the hit "
           "point from the true surface (analytic shape; teapot: tessellated reference refined by Newton); "
           "holes = rays that hit the true surface but not the representation; image RMSE/PSNR against "
           "the MLS reference (k = 16, double) on display-encoded values. CPU rays/s: primary rays through "
           "the core on all threads of that host (prt-accuracy)." % (
               " --quick" if meta["quick"] else "", " --gpu" if meta["gpu"] else "", meta["started"],
               meta["git"], meta["host"], meta["cpus"], meta["seconds"]), ""]
    if meta.get("note"):
        out += [meta["note"], ""]
    hdr = ["model", "surface", "setting", "prep s", "peak MB", "B/point", "Mrays/s (CPU)", "err mean", "err p99",
           "err max", "holes", "false hits", "normal deg", "RMSE", "PSNR dB"]
    out.append("| " + " | ".join(hdr) + " |")
    out.append("|" + "---|" * len(hdr))
    for r in rows:
        out.append("| " + " | ".join([
            r["model"], r["surface"], r["setting"], fmt(r["prep_seconds"]), fmt(r["prep_peak_mb"]),
            fmt(r["bytes_per_point"]), fmt(r["rays_per_s"] / 1e6 if r["rays_per_s"] else None),
            fmt(r.get("hit_error_mean")), fmt(r.get("hit_error_p99")), fmt(r.get("hit_error_max")),
            fmt(r.get("hole_rate")), fmt(r.get("false_hit_rate")), fmt(r.get("normal_error_deg")),
            fmt(r.get("image_rmse")), fmt(r.get("image_psnr_db"))]) + " |")
    out += ["", "## Preprocessing steps", "", "| model | step | seconds | peak MB |", "|---|---|---|---|"]
    for model, steps in result["prep"].items():
        for step, v in steps.items():
            out.append("| %s | %s | %s | %s |" % (model, step, fmt(v["seconds"]), fmt(v["peak_mb"])))
    if result["bench"]:
        out += ["", "## prt-bench per surface (rays/s by kind, Grays/s)", "",
                "| model | surface | backend | device | res | primary | shadow scenario | shadow rays | "
                "reflect4 scenario | secondary rays | note |", "|---|---|---|---|---|---|---|---|---|---|---|"]
        for b in result["bench"]:
            out.append("| %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |" % (
                b["model"], b["surface"], b["backend"], b.get("device", "-"), b["resolution"],
                fmt(b.get("primary_grays_per_s")), fmt(b.get("shadow_grays_per_s")),
                fmt(b.get("shadow_only_grays_per_s")), fmt(b.get("reflect4_grays_per_s")),
                fmt(b.get("secondary_only_grays_per_s")), b.get("error", "")))
    if result.get("fidelity"):
        out += ["", "## Fidelity against ground truth (issue 15)", "",
                "`prt-fidelity` from several views at the stated resolution: the reference mesh (Stanford "
                "reconstructions, the meshes the armadillo and dragon points come from) or the analytic shape "
                "of a laser-scan simulation (`prt-synth --scan`, range noise 5e-4 of the size, 1 % outliers, "
                "then `prt-import` like a real scan; the room seen from its scanner). Holes and false hits are "
                "percentages of the pixels where the scan has data; depth error and normal error are medians, "
                "depth in local point spacings. Every surface at its defaults (`no_deep`: splats without deep "
                "blending; `k8`: MLS with 8 samples per cell). Target: issue 15's (met / missed).", "",
                "| case | points | surface | setting | prep s | peak MB | Mrays/s (CPU) | holes % | holes % with edges "
                "| false hits % | depth (spacings) | normal deg | target |",
                "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
        for r in result["fidelity"]:
            out.append("| %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |" % (
                r["model"], r["points"], r["surface"], r["setting"], fmt(r["prep_seconds"]), fmt(r["prep_peak_mb"]),
                fmt(r["rays_per_s"] / 1e6 if r.get("rays_per_s") else None), fmt(100 * r["hole_rate"]),
                fmt(100 * r["hole_rate_with_edges"]), fmt(100 * r["false_hit_rate"]),
                fmt(r.get("depth_error_spacings")), fmt(r.get("normal_error_deg")), r.get("target", "")))
        out += ["", "![Pareto plot of the fidelity cases: CPU time per ray against the median depth error in "
                "spacings](pareto_fidelity.png)"]
    if result["failures"]:
        out += ["", "## Failures", ""] + ["- " + f for f in result["failures"]]
    out += ["", "![Pareto plot: CPU time per ray against mean hit error](pareto.png)", ""]
    return "\n".join(out)


def write_all(out_dir, result):
    def atomic(path, text):
        with open(path + ".tmp", "w") as f:
            f.write(text)
        os.replace(path + ".tmp", path)

    atomic(os.path.join(out_dir, "results.json"), json.dumps(result, indent=1))
    with open(os.path.join(out_dir, "results.csv.tmp"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=COLUMNS, extrasaction="ignore")
        w.writeheader()
        for r in result["runs"]:
            w.writerow(r)
    os.replace(os.path.join(out_dir, "results.csv.tmp"), os.path.join(out_dir, "results.csv"))
    atomic(os.path.join(out_dir, "RESULTS.md"), markdown(result))
    if any(r.get("hit_error_mean") for r in result["runs"]):
        plot_pareto(result["runs"], os.path.join(out_dir, "pareto.png"))
    if any(r.get("depth_error_spacings") for r in result.get("fidelity", [])):
        plot_pareto(result["fidelity"], os.path.join(out_dir, "pareto_fidelity.png"), "depth_error_spacings",
                    "cpu time per ray (ns, log) against median depth error (local spacings, log)")
