#!/usr/bin/env python3
"""PointRT speed/accuracy suite (issue 9), driven by scripts/suite/run.sh.

For each model (prt-synth sphere, torus and cube at 100k/1M/10M points; the teapot's Bezier
patches; the real scans of ../shared/data: kitten, bunny, dragon, armadillo, the PCL mug scene) and
each surface setting, it records:
  preprocessing: seconds and peak resident memory of every tool run (os.wait4 rusage), the
                 surface's bytes per point (prt-accuracy: bytes of the sections the tracer reads);
  speed:         CPU rays/s of primary rays through the core (prt-accuracy, median of runs), and
                 prt-bench's rays/s by ray kind (primary, shadow, secondary) per surface, on the CPU
                 or with --gpu on the CUDA backend;
  accuracy:      hit-point error against the analytic surface (mean, p99, max of the distance to
                 the true surface, relative to the model's diagonal), hole and false-hit rates; for
                 patches against an independent tessellated reference refined by Newton;
  image error:   RMSE and PSNR of the shaded image against the MLS reference (k = 16, double).
Output in OUT_DIR: results.json (everything), results.csv (one row per run), pareto.png (CPU time
per ray against mean hit error, one panel per model), RESULTS.md (the tables), log.txt.
Python standard library only (no numpy or matplotlib needed; the PNG is written with zlib).

Scans need prt-import with PCL (normal estimation) and OpenMesh (meshes). On a machine without them
(the GPU host), import them elsewhere with --import-scans DIR and pass --scan-pools DIR there.
"""
import argparse
import json
import os
import shutil
import signal
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import report  # noqa: E402  (same folder)

REPO = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
SHARED = os.environ.get("PRT_SHARED_DATA_DIR", os.path.join(REPO, "..", "shared", "data"))

# Fidelity against ground truth (issue 15): label, how the points are made, the reference, the
# views. "import": prt-import arguments (paths under SHARED); "scan": prt-synth --scan arguments
# (the pool then goes through prt-import like a real scan, and the reference is its analytic shape).
BUNNY = "points/stanford_bunny/"
FIDELITY_CASES = [
    ("bunny_10_scans", "import", ["--poses", BUNNY + "data/bun.conf"], BUNNY + "reconstruction/bun_zipper.ply",
     "orbit"),
    ("bunny_bun000", "import", ["--poses", BUNNY + "data/bun.conf", BUNNY + "data/bun000.ply"],
     BUNNY + "reconstruction/bun_zipper.ply", "orbit"),
    ("armadillo_vertices", "import", ["points/stanford_armadillo/armadillo.off"],
     "points/stanford_armadillo/armadillo.off", "orbit"),
    ("armadillo_10pct", "import", ["points/stanford_armadillo/armadillo.off", "--keep-fraction", "0.1"],
     "points/stanford_armadillo/armadillo.off", "orbit"),
    ("dragon_vertices", "import", ["points/stanford_dragon/dragon_small.obj"],
     "points/stanford_dragon/dragon_small.obj", "orbit"),
    ("dragon_10pct", "import", ["points/stanford_dragon/dragon_small.obj", "--keep-fraction", "0.1"],
     "points/stanford_dragon/dragon_small.obj", "orbit"),
    ("sphere_laser", "scan", ["sphere", "--scanners", "3", "--range-noise", "0.0005", "--outliers", "0.01"], None,
     "orbit"),
    ("torus_laser", "scan", ["torus", "--scanners", "4", "--range-noise", "0.0005", "--outliers", "0.01"], None,
     "orbit"),
    ("room_laser", "scan", ["room", "--range-noise", "0.0005", "--outliers", "0.01"], None, "sensors"),
]
# Issue 15's targets: (holes, false hits) as fractions of the data-covered pixels, per case group.
FIDELITY_TARGETS = {
    "bunny_10_scans": {"holes": 0.003, "false_hits": 0.003, "depth": 0.25, "normal_deg": 5.0},
    "bunny_bun000": {"holes": 0.005, "false_hits": 0.005},
    "armadillo_10pct": {"holes": 0.01, "false_hits": 0.005, "surfaces": ["splats", "mls"]},
    "dragon_10pct": {"holes": 0.01, "false_hits": 0.005, "surfaces": ["splats", "mls"]},
    "sphere_laser": {"holes": 0.003, "false_hits": 0.003, "depth": 0.25, "normal_deg": 5.0},
    "torus_laser": {"holes": 0.003, "false_hits": 0.003, "depth": 0.25, "normal_deg": 5.0},
    "room_laser": {"holes": 0.003, "false_hits": 0.003, "depth": 0.25, "normal_deg": 5.0},
}

# The real scans (../shared/data/README.md): label, path under SHARED, prt-import arguments.
SCANS = [
    ("kitten", "points/cgal_kitten/kitten.xyz", []),
    ("bunny", "points/stanford_bunny/reconstruction/bun_zipper.ply", ["--mesh-mode", "points"]),
    ("dragon", "points/stanford_dragon/dragon_small.obj", []),
    ("armadillo", "points/stanford_armadillo/armadillo.off", []),
    ("mug_scene", "points/pcl/table_scene_mug_stereo_textured.pcd", []),
]


class Suite:
    def __init__(self, args):
        self.args = args
        self.out = os.path.abspath(args.out_dir)
        self.bin = os.path.abspath(args.bin)
        self.rows = []    # prt-accuracy runs
        self.prep = {}    # model -> step -> {seconds, peak_mb}
        self.bench = []   # prt-bench runs
        self.fidelity = []  # prt-fidelity runs (issue 15)
        self.failures = []
        os.makedirs(os.path.join(self.out, "models"), exist_ok=True)
        os.makedirs(os.path.join(self.out, "runs"), exist_ok=True)
        os.makedirs(os.path.join(self.out, "images"), exist_ok=True)
        self.log = open(os.path.join(self.out, "log.txt"), "a")
        self.t0 = time.time()

    def say(self, msg):
        line = "[%6.0f s] %s" % (time.time() - self.t0, msg)
        self.log.write(line + "\n")
        self.log.flush()
        if not self.args.quiet:
            print(line, file=sys.stderr, flush=True)

    def tool(self, name):
        path = os.path.join(self.bin, name)
        if not os.path.exists(path):
            raise SystemExit("suite: %s: not built (build it, or pass --bin DIR)" % path)
        return path

    def run(self, cmd, check=True):
        """Runs a command; returns (returncode, seconds, stdout, stderr)."""
        self.log.write("$ " + " ".join(cmd) + "\n")
        t = time.time()
        p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        out, err = p.communicate()
        seconds = time.time() - t
        self.log.write(out + err)
        if check and p.returncode != 0:
            raise RuntimeError("%s failed (%d): %s" % (os.path.basename(cmd[0]), p.returncode,
                                                      err.strip().splitlines()[-1] if err.strip() else ""))
        return p.returncode, seconds, out, err

    def timed(self, model, step, cmd):
        """A preprocessing step: wall seconds and peak RSS of the child (os.wait4 rusage)."""
        self.log.write("$ " + " ".join(cmd) + "\n")
        t = time.time()
        p = subprocess.Popen(cmd + ["--quiet"], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        err = p.stderr.read()
        _, status, usage = os.wait4(p.pid, 0)
        seconds = time.time() - t
        p.returncode = os.waitstatus_to_exitcode(status)
        if p.returncode != 0:
            raise RuntimeError("%s: %s" % (step, err.decode(errors="replace").strip()))
        peak_mb = usage.ru_maxrss / 1024.0  # Linux: kilobytes
        self.prep.setdefault(model, {})[step] = {"seconds": seconds, "peak_mb": peak_mb}
        self.say("  %s %s: %.2f s, %.0f MB peak" % (model, step, seconds, peak_mb))

    # ---- models ---------------------------------------------------------------------------------

    def synthetic(self, shape, n):
        name = "%s_%s" % (shape, report.count_label(n))
        d = os.path.join(self.out, "models", name)
        os.makedirs(d, exist_ok=True)
        pools = {}
        synth = os.path.join(d, "synth.pool")
        self.timed(name, "synth", [self.tool("prt-synth"), shape, "-n", str(n), "-o", synth])
        radii = os.path.join(d, "radii.pool")
        self.timed(name, "radii", [self.tool("prt-radii"), synth, "-o", radii])
        for x in self.settings["leaf_sizes"]:
            oc = os.path.join(d, "octree_X%d.pool" % x)
            self.timed(name, "octree_X%d" % x, [self.tool("prt-octree"), radii, "-o", oc, "-X", str(x)])
            pools["octree_X%d" % x] = oc
            if x == 32:
                # prt-cull's policies side by side (issue 20): greedy keeps the label "cull_X32".
                for policy in self.settings["cull_policies"]:
                    key = cull_key(policy, x)
                    cu = os.path.join(d, key + ".pool")
                    self.timed(name, key, [self.tool("prt-cull"), oc, "-o", cu, "--policy", policy])
                    pools[key] = cu
        mls = os.path.join(d, "mls.pool")
        self.timed(name, "mls", [self.tool("prt-mls"), radii, "-o", mls])
        pools["mls"] = mls
        for level in self.settings["iso_levels"]:
            iso = os.path.join(d, "iso_L%d.pool" % level)
            self.timed(name, "iso_L%d" % level, [self.tool("prt-iso"), synth, "-o", iso, "--max-level",
                                                 str(level), "--storage", "both"])
            pools["iso_L%d" % level] = iso
        return name, n, pools

    def scan(self, label, path, import_args):
        """The pools of a real scan: imported here, or taken from --scan-pools (LABEL.pool)."""
        d = os.path.join(self.out, "models", label)
        os.makedirs(d, exist_ok=True)
        if self.args.scan_pools:  # read in place: the tools only read their input
            imp = os.path.join(self.args.scan_pools, label + ".pool")
        else:
            imp = os.path.join(d, "import.pool")
            self.timed(label, "import", [self.tool("prt-import"), path, "-o", imp] + import_args)
        radii = os.path.join(d, "radii.pool")
        self.timed(label, "radii", [self.tool("prt-radii"), imp, "-o", radii])
        oc = os.path.join(d, "octree_X32.pool")
        self.timed(label, "octree_X32", [self.tool("prt-octree"), radii, "-o", oc, "-X", "32"])
        mls = os.path.join(d, "mls.pool")
        self.timed(label, "mls", [self.tool("prt-mls"), radii, "-o", mls])
        pools = {"octree_X32": oc, "mls": mls}
        for level in self.settings["iso_levels"]:
            iso = os.path.join(d, "iso_L%d.pool" % level)
            self.timed(label, "iso_L%d" % level, [self.tool("prt-iso"), radii, "-o", iso, "--max-level",
                                                  str(level), "--storage", "both"])
            pools["iso_L%d" % level] = iso
        return pools

    def teapot(self):
        src = os.path.join(SHARED, "bezier", "teapot")
        if not os.path.exists(src):
            self.say("teapot: %s absent, skipped" % src)
            return None
        d = os.path.join(self.out, "models", "teapot")
        os.makedirs(d, exist_ok=True)
        pools = {}
        for depth in self.settings["patch_depths"]:
            p = os.path.join(d, "patches_D%d.pool" % depth)
            self.timed("teapot", "patches_D%d" % depth,
                       [self.tool("prt-patches"), src, "-o", p, "--depth", str(depth)])
            pools["patches_D%d" % depth] = p
        return pools

    # ---- measurements ---------------------------------------------------------------------------

    def accuracy(self, model, points, surface, pool, prep_steps, label, extra):
        tag = "%s__%s__%s" % (model, surface, label)
        js = os.path.join(self.out, "runs", tag + ".json")
        img = os.path.join(self.out, "images", tag + ".pfm")
        cmd = [self.tool("prt-accuracy"), pool, "--surface", surface, "--width", str(self.settings["res"]),
               "--height", str(self.settings["res"]), "--repeat", str(self.settings["repeat"]), "--json", js,
               "--image", img, "--quiet"] + extra
        try:
            self.run(cmd)
        except RuntimeError as e:
            self.failures.append("%s: %s" % (tag, e))
            self.say("  FAILED %s: %s" % (tag, e))
            return None
        j = json.load(open(js))
        prep = self.prep.get(model, {})
        row = {
            "model": model, "points": points, "surface": surface, "setting": label,
            "prep_seconds": sum(prep[s]["seconds"] for s in prep_steps if s in prep),
            "prep_peak_mb": max([prep[s]["peak_mb"] for s in prep_steps if s in prep] or [0]),
            "bytes_per_point": j.get("bytes_per_point"),
            "rays_per_s": j["rays_per_s"], "rays_per_s_best": j.get("rays_per_s_best"), "ns_per_ray": 1e9 / j["rays_per_s"] if j["rays_per_s"] else None,
            "hit_fraction": j["hit_fraction"], "truth": j["truth"],
            "hole_rate": j.get("hole_rate"), "false_hit_rate": j.get("false_hit_rate"),
            "normal_error_deg": j.get("normal_error_degrees_mean"),
            "image": img, "json": js, "threads": j["threads"],
        }
        for k in ("mean", "p99", "max"):
            row["hit_error_" + k] = (j.get("hit_error") or {}).get(k)
        self.rows.append(row)
        self.say("  %-16s %-8s %-22s %9.3f Mrays/s  err mean %s  holes %s" % (
            model, surface, label, j["rays_per_s"] / 1e6, report.fmt(row["hit_error_mean"]),
            report.fmt(row["hole_rate"])))
        return row

    def measure_points(self, model, points, pools):
        s = self.settings
        # MLS: k = 4, 8, 16 in float (the renderer's precision) and the reference (k = 16, double).
        ref = self.accuracy(model, points, "mls", pools["mls"], ["radii", "mls"], "reference_k16_double",
                            ["--mls-k", "16", "--mls-precision", "double"])
        for k in s["mls_k"]:
            self.accuracy(model, points, "mls", pools["mls"], ["radii", "mls"], "k%d" % k, ["--mls-k", str(k)])
        # Splats: leaf size, prt-cull on/off, deep blending on/off, runtime leaf culling.
        for key, pool in pools.items():
            if not (key.startswith("octree_") or key.startswith("cull_")):
                continue
            x = key.split("_X")[1]
            culled = key.startswith("cull_")
            policy = key[len("cull_"):].split("_X")[0] if culled and not key.startswith("cull_X") else ""
            steps = ["radii", "octree_X" + x] + ([key] if culled else [])
            for deep in s["deep"]:
                for lc in s["leaf_culling"]:
                    label = "X%s%s%s%s_lc%d" % (x, "_culled" if culled else "", "_" + policy if policy else "",
                                                "_deep" if deep else "", lc)
                    extra = ["--leaf-culling", str(lc), "--deep-blending" if deep else "--no-deep-blending"]
                    self.accuracy(model, points, "splats", pool, steps, label, extra)
        # ISO: levels, q8/f32, refinement.
        for key, pool in pools.items():
            if not key.startswith("iso_"):
                continue
            for storage in ("q8", "f32"):
                for refine in s["iso_refine"]:
                    self.accuracy(model, points, "iso", pool, [key], "%s_%s_r%d" % (key[4:], storage, refine),
                                  ["--iso-storage", storage, "--iso-refine", str(refine)])
        if ref:
            self.image_errors(model, ref)

    def measure_patches(self, pools):
        for key, pool in pools.items():
            for it in self.settings["patch_iterations"]:
                for tol in self.settings["patch_tolerances"]:
                    for prec in self.settings["patch_precisions"]:
                        self.accuracy("teapot", None, "patches", pool, [key],
                                      "D%s_it%d_tol%g%s" % (key[-1], it, tol, "_f32" if prec == "float" else ""),
                                      ["--patch-iterations", str(it), "--patch-tolerance", str(tol),
                                       "--patch-precision", prec])

    def image_errors(self, model, ref):
        for row in self.rows:
            if row["model"] != model or row is ref:
                continue
            js = row["json"].replace(".json", ".compare.json")
            try:
                self.run([self.tool("prt-accuracy"), "--quiet", "compare", ref["image"], row["image"], "--json",
                          js])
                c = json.load(open(js))
                row["image_rmse"] = c["rmse"]
                row["image_psnr_db"] = c["psnr_db"] if c["psnr_db"] != "inf" else None
            except RuntimeError as e:
                self.failures.append("compare %s: %s" % (row["image"], e))

    # ---- prt-bench per surface -------------------------------------------------------------------

    def bench_surface(self, model, surface, pool, camera=None, light=None):
        """prt-bench on one surface; without a camera prt-bench frames the pool itself."""
        js = os.path.join(self.out, "runs", "bench_%s_%s.json" % (model, surface))
        b = self.settings["bench"]
        if camera is None:
            where = [pool, "--surface", surface]
        else:
            scene = {"camera": camera, "lights": [{"type": "point", "position": light, "intensity": 1.0}],
                     "materials": [{"name": "m", "diffuse": [0.8, 0.8, 0.8], "reflectivity": 0.0}],
                     "models": [{"pool": pool, "surface": surface, "material": "m"}]}
            sp = os.path.join(self.out, "runs", "scene_%s_%s.json" % (model, surface))
            with open(sp, "w") as f:
                json.dump(scene, f, indent=2)
            where = ["--scene", sp]
        cmd = [self.tool("prt-bench")] + where + ["--backend", b["backend"], "--width", str(b["res"]),
               "--height", str(b["res"]), "--frames", str(b["frames"]), "--warmup", str(b["warmup"]),
               "--json", js, "--quiet"]
        rc, _, out, err = self.run(cmd, check=False)
        entry = {"model": model, "surface": surface, "backend": b["backend"], "resolution": b["res"]}
        if rc != 0:
            entry["error"] = (err.strip().splitlines() or ["exit %d" % rc])[-1]
            self.say("  bench %s %s: %s" % (model, surface, entry["error"]))
        else:
            j = json.load(open(js))
            entry["device"] = j.get("device")
            for sc in j.get("scenarios", []):
                entry[sc["name"] + "_grays_per_s"] = sc["grays_per_s"]
                entry[sc["name"] + "_ms"] = sc["median_ms"]
                if sc["name"] == "shadow":
                    entry["shadow_only_grays_per_s"] = sc["shadow_grays_per_s"]
                if sc["name"] == "reflect4":
                    entry["secondary_only_grays_per_s"] = sc["secondary_grays_per_s"]
                entry["sanitized"] = entry.get("sanitized", 0) + sc.get("sanitized", 0)
            self.say("  bench %s %s: primary %s Grays/s" % (model, surface,
                                                             report.fmt(entry.get("primary_grays_per_s"))))
        self.bench.append(entry)


    # ---- fidelity against ground truth (issue 15) -------------------------------------------------

    def fidelity_case(self, label, kind, args, reference, views):
        """Builds every surface at its defaults and measures each with prt-fidelity."""
        d = os.path.join(self.out, "models", label)
        os.makedirs(d, exist_ok=True)
        imp = os.path.join(d, "import.pool")
        if kind == "scan":
            raw = os.path.join(d, "scan.pool")
            self.timed(label, "scan", [self.tool("prt-synth")] + args[:1] + ["--scan"] + args[1:] + ["-o", raw])
            self.timed(label, "import", [self.tool("prt-import"), raw, "-o", imp])
        else:
            paths = [os.path.join(SHARED, a) if a.startswith("points/") else a for a in args]
            self.timed(label, "import", [self.tool("prt-import")] + paths + ["-o", imp])
        steps = [("radii", "prt-radii", []), ("octree", "prt-octree", []), ("cull", "prt-cull", []),
                 ("iso", "prt-iso", []), ("mls", "prt-mls", [])]
        pool = os.path.join(d, "surfaces.pool")
        src = imp
        octree = os.path.join(d, "octree.pool")
        for step, tool, extra in steps:
            self.timed(label, step, [self.tool(tool), src, "-o", pool] + extra)
            src = pool
            if step == "octree":
                shutil.copyfile(pool, octree)
        res = self.settings["fidelity_res"]
        runs = [("splats", "default", []), ("splats", "no_deep", ["--no-deep-blending"]), ("iso", "default", []),
                ("mls", "default", []), ("mls", "k8", ["--mls-k", "8"])]
        prep = self.prep.get(label, {})
        prep_of = {"splats": ["import", "radii", "octree", "cull"], "iso": ["import", "radii", "iso"],
                   "mls": ["import", "radii", "mls"]}
        # prt-cull's policies side by side on the same octree (issue 20): rows splats / cull_POLICY.
        pool_of = {}
        for policy in self.settings["cull_policies"]:
            cu = os.path.join(d, "cull_%s.pool" % policy)
            self.timed(label, "cull_" + policy, [self.tool("prt-cull"), octree, "-o", cu, "--policy", policy])
            runs.append(("splats", "cull_" + policy, []))
            pool_of["cull_" + policy] = cu
        for surface, setting, extra in runs:
            tag = "fidelity_%s__%s__%s" % (label, surface, setting)
            js = os.path.join(self.out, "runs", tag + ".json")
            cmd = [self.tool("prt-fidelity"), pool_of.get(setting, pool), "--surface", surface,
                   "--width", str(res), "--height", str(res),
                   "--views-from", views, "--json", js, "--quiet"] + extra
            if reference:
                cmd += ["--reference", os.path.join(SHARED, reference)]
            if self.args.fidelity_images:
                cmd += ["--images", os.path.join(self.out, "images", tag)]
            try:
                self.run(cmd)
            except RuntimeError as e:
                self.failures.append("%s: %s" % (tag, e))
                self.say("  FAILED %s: %s" % (tag, e))
                continue
            j = json.load(open(js))
            sj = j["surfaces"][surface]
            med = lambda k: (sj.get(k) or {}).get("median")  # noqa: E731
            steps_used = prep_of[surface] + (["scan"] if kind == "scan" else [])
            if setting in pool_of:
                steps_used = [st for st in steps_used if st != "cull"] + [setting]
            row = {
                "model": label, "surface": surface, "setting": setting, "points": j["input_points"],
                "views": j["views"], "resolution": res, "reference": j["reference"]["kind"],
                "prep_seconds": sum(prep[s]["seconds"] for s in steps_used if s in prep),
                "prep_peak_mb": max([prep[s]["peak_mb"] for s in steps_used if s in prep] or [0]),
                "surface_bytes": sj.get("surface_bytes"), "rays_per_s": sj.get("rays_per_s"),
                "ns_per_ray": 1e9 / sj["rays_per_s"] if sj.get("rays_per_s") else None,
                "covered_pixels": sj["covered_pixels"], "hole_rate": sj["hole_rate"],
                "hole_rate_with_edges": sj["hole_rate_with_edges"], "false_hit_rate": sj["false_hit_rate"],
                "depth_error_spacings": med("depth_error_spacings"),
                "surface_distance_spacings": med("surface_distance_spacings"),
                "normal_error_deg": med("normal_error_degrees"), "threads": j["threads"], "json": js,
            }
            t = FIDELITY_TARGETS.get(label)
            if t and setting == "default" and surface in t.get("surfaces", ["splats", "iso", "mls"]):
                misses = []
                if row["hole_rate"] > t["holes"]:
                    misses.append("holes")
                if row["false_hit_rate"] > t["false_hits"]:
                    misses.append("false hits")
                if "depth" in t and (row["depth_error_spacings"] or 0) > t["depth"]:
                    misses.append("depth")
                if "normal_deg" in t and (row["normal_error_deg"] or 0) > t["normal_deg"]:
                    misses.append("normals")
                row["target"] = "missed: " + ", ".join(misses) if misses else "met"
            self.fidelity.append(row)
            self.say("  %-20s %-7s %-8s holes %s%%  false %s%%  depth %s  normal %s deg  %s" % (
                label, surface, setting, report.fmt(100 * row["hole_rate"]), report.fmt(100 * row["false_hit_rate"]),
                report.fmt(row["depth_error_spacings"]), report.fmt(row["normal_error_deg"]), row.get("target", "")))


class Interrupted(Exception):
    """SIGTERM during a run."""


def cull_key(policy, x):
    """The pool key of prt-cull --policy POLICY on the X-leaf octree: cull_X32 for greedy (the rows'
    labels before issue 20), cull_thesis_X32 for the thesis's."""
    return "cull_X%d" % x if policy == "greedy" else "cull_%s_X%d" % (policy, x)


def scan_points(suite, pool):
    """Points of a pool, from prt-info's first line of counts ("points: N ...")."""
    _, _, out, _ = suite.run([suite.tool("prt-info"), pool])
    for line in out.splitlines():
        if line.startswith("points:"):
            return int(line.split()[1])
    return None


def settings_for(args):
    quick = args.quick
    s = {
        "sizes": [100_000] if quick else ([1_000_000] if args.gpu else [100_000, 1_000_000, 10_000_000]),
        "shapes": ["sphere", "torus", "cube"],
        "leaf_sizes": [32] if quick else [16, 32, 64],
        "deep": [False, True],
        "leaf_culling": [2] if quick else [0, 2],
        "cull_policies": ["greedy", "thesis"],
        "iso_levels": [8, 10] if quick else [7, 8, 9, 10, 11, 12],
        "iso_refine": [0, 2],
        "mls_k": [4, 8, 16],
        "patch_depths": [4, 6, 8],
        "patch_iterations": [4, 16] if quick else [2, 4, 8, 16],
        "patch_tolerances": [1e-12] if quick else [1e-6, 1e-12],
        "patch_precisions": ["double", "float"],
        "res": 128 if quick else 256,
        "fidelity_res": 256 if quick else 1024,
        "repeat": 15 if quick else 3,
        "bench": {"backend": "cuda" if args.gpu else "cpu", "res": 1024 if args.gpu else (128 if quick else 256),
                  "frames": 20 if args.gpu else 3, "warmup": 3 if args.gpu else 1},
    }
    if args.fidelity_res:
        s["fidelity_res"] = args.fidelity_res
    if args.shapes:
        s["shapes"] = [] if args.shapes == "none" else args.shapes.split(",")
    if args.sizes:
        s["sizes"] = [int(float(x)) for x in args.sizes.split(",")]
    return s


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out_dir", nargs="?", help="folder for models, runs, images and the reports (created)")
    ap.add_argument("--quick", action="store_true",
                    help="CI-size run: 100k points, fewer settings, 128x128 rays (default: off)")
    ap.add_argument("--gpu", action="store_true",
                    help="prt-bench on the CUDA backend at 1024x1024; models of 1M points unless --quick "
                         "or --sizes (default: off: CPU backend)")
    ap.add_argument("--sizes", default="",
                    help="comma-separated point counts replacing the default sizes (default: by mode)")
    ap.add_argument("--shapes", default="", help="comma-separated prt-synth shapes, or 'none' (default: sphere,torus,cube)")
    ap.add_argument("--bin", default=os.path.join(REPO, "build", "bin"),
                    help="folder of the built tools (default: REPO/build/bin)")
    ap.add_argument("--publish", action="store_true",
                    help="also copy RESULTS.md and pareto.png to scripts/suite/ (default: off)")
    ap.add_argument("--baseline", default="",
                    help="results.json of an earlier run: compare.py checks this run against it and the exit "
                         "status is 1 on a flag (default: none)")
    ap.add_argument("--no-bench", action="store_true", help="skip the prt-bench runs (default: off)")
    ap.add_argument("--note", default="", help="a sentence for RESULTS.md about the machine or the run (default: none)")
    ap.add_argument("--scans", default="",
                    help="comma-separated real scans to measure, of: %s; 'none' for none (default: every one "
                         "present)" % ",".join(x[0] for x in SCANS))
    ap.add_argument("--scan-pools", default="",
                    help="folder of pre-imported scans (LABEL.pool) used instead of prt-import (default: import)")
    ap.add_argument("--import-scans", default="", metavar="DIR",
                    help="only import the scans into DIR/LABEL.pool (for --scan-pools elsewhere) and exit")
    ap.add_argument("--fidelity", default="",
                    help="comma-separated fidelity cases (issue 15), of: %s; 'none' for none (default: every one "
                         "whose data is present)" % ",".join(x[0] for x in FIDELITY_CASES))
    ap.add_argument("--fidelity-res", type=int, default=0,
                    help="prt-fidelity's image size (default: 1024, 256 with --quick)")
    ap.add_argument("--fidelity-images", action="store_true",
                    help="also write prt-fidelity's per-view images under OUT_DIR/images (default: off)")
    ap.add_argument("--quiet", action="store_true", help="no progress on stderr (default: off)")
    args = ap.parse_args()
    wanted = [x for x in SCANS if not args.scans or x[0] in args.scans.split(",")]
    if args.import_scans:
        os.makedirs(args.import_scans, exist_ok=True)
        for label, rel, import_args in wanted:
            src = os.path.join(SHARED, rel)
            if not os.path.exists(src):
                print("suite: %s absent, skipped" % src, file=sys.stderr)
                continue
            out = os.path.join(args.import_scans, label + ".pool")
            subprocess.run([os.path.join(os.path.abspath(args.bin), "prt-import"), src, "-o", out, "--quiet"]
                           + import_args, check=True)
            print("suite: %s -> %s" % (src, out), file=sys.stderr)
        return 0
    if not args.out_dir:
        ap.error("the output folder is required (except with --import-scans)")
    s = Suite(args)
    s.settings = settings_for(args)
    started = time.strftime("%Y-%m-%d %H:%M:%S")
    models, scans, tp = [], [], None

    def interrupted(signum, frame):
        signal.signal(signal.SIGTERM, signal.SIG_IGN)  # once: the reports are written next
        raise Interrupted("signal %d" % signum)

    # `timeout` (scripts/suite/device.sh bounds the run) sends SIGTERM: the reports still get written
    # with what was measured, and the run is listed as a failure.
    signal.signal(signal.SIGTERM, interrupted)
    try:
        for n in s.settings["sizes"]:
            for shape in s.settings["shapes"]:
                s.say("model %s %d" % (shape, n))
                try:
                    models.append(s.synthetic(shape, n))
                except RuntimeError as e:
                    s.failures.append("%s %d: %s" % (shape, n, e))
                    s.say("  FAILED: %s" % e)
        for name, n, pools in models:
            s.say("measure %s" % name)
            s.measure_points(name, n, pools)
        scans = []
        for label, rel, import_args in ([] if args.scans == "none" else wanted):
            src = os.path.join(SHARED, rel)
            if not args.scan_pools and not os.path.exists(src):
                s.say("%s: %s absent, skipped" % (label, src))
                continue
            if args.scan_pools and not os.path.exists(os.path.join(args.scan_pools, label + ".pool")):
                s.say("%s: not in %s, skipped" % (label, args.scan_pools))
                continue
            s.say("scan %s" % label)
            try:
                kp = s.scan(label, src, import_args)
                s.measure_points(label, scan_points(s, kp["mls"]), kp)
                scans.append((label, kp))
            except RuntimeError as e:
                s.failures.append("%s: %s" % (label, e))
                s.say("  FAILED: %s" % e)
        for label, kind, fargs, ref, views in ([] if args.fidelity == "none" else FIDELITY_CASES):
            if args.fidelity and label not in args.fidelity.split(","):
                continue
            needs = [a for a in fargs if a.startswith("points/")] + ([ref] if ref else [])
            missing = [n for n in needs if not os.path.exists(os.path.join(SHARED, n))]
            if missing:
                s.say("fidelity %s: %s absent, skipped" % (label, os.path.join(SHARED, missing[0])))
                continue
            s.say("fidelity %s" % label)
            try:
                s.fidelity_case(label, kind, fargs, ref, views)
            except RuntimeError as e:
                s.failures.append("fidelity %s: %s" % (label, e))
                s.say("  FAILED: %s" % e)
        tp = s.teapot()
        if tp:
            s.say("measure teapot")
            s.measure_patches(tp)
        if not args.no_bench:
            cam = {"position": [0.0, 1.2, 4.0], "look_at": [0.0, 0.0, 0.0], "fov_y_degrees": 40.0}
            for name, n, pools in models:
                s.say("prt-bench per surface on %s (%s)" % (name, s.settings["bench"]["backend"]))
                s.bench_surface(name, "splats", pools["octree_X32"], cam, [2.0, 4.0, 3.0])
                s.bench_surface(name, "iso", pools["iso_L%d" % s.settings["iso_levels"][-1]], cam, [2.0, 4.0, 3.0])
                s.bench_surface(name, "mls", pools["mls"], cam, [2.0, 4.0, 3.0])
            for label, kp in scans:
                s.say("prt-bench per surface on %s" % label)
                s.bench_surface(label, "splats", kp["octree_X32"])
                s.bench_surface(label, "iso", kp["iso_L%d" % s.settings["iso_levels"][-1]])
                s.bench_surface(label, "mls", kp["mls"])
            if tp:
                tcam = {"position": [0.0, -9.0, 5.0], "look_at": [0.0, 0.0, 1.5], "up": [0.0, 0.0, 1.0],
                        "fov_y_degrees": 40.0}
                s.bench_surface("teapot", "patches", tp["patches_D%d" % s.settings["patch_depths"][0]], tcam,
                                [3.0, -6.0, 8.0])
    except (Interrupted, KeyboardInterrupt) as e:
        s.failures.append("interrupted (%s): the reports hold what was measured before" % (e or "Ctrl-C"))
        s.say("INTERRUPTED: writing the reports")
    meta = {"note": args.note, "started": started, "seconds": time.time() - s.t0, "quick": args.quick, "gpu": args.gpu,
            "host": os.uname().nodename, "cpus": os.cpu_count(), "settings": s.settings,
            "git": subprocess.run(["git", "-C", REPO, "rev-parse", "--short", "HEAD"], capture_output=True,
                                  text=True).stdout.strip()}
    result = {"meta": meta, "runs": s.rows, "prep": s.prep, "bench": s.bench, "fidelity": s.fidelity,
              "failures": s.failures}
    report.write_all(s.out, result)
    if args.publish:
        for f in ("RESULTS.md", "pareto.png", "pareto_fidelity.png"):
            if not os.path.exists(os.path.join(s.out, f)):
                continue
            shutil.copy(os.path.join(s.out, f), os.path.join(REPO, "scripts", "suite", f))
    s.say("done: %d runs, %d bench runs, %d failures; %s" % (len(s.rows), len(s.bench), len(s.failures),
                                                            os.path.join(s.out, "RESULTS.md")))
    status = 1 if s.failures else 0
    if args.baseline:
        guard = subprocess.run([sys.executable, os.path.join(os.path.dirname(os.path.abspath(__file__)), "compare.py"),
                                args.baseline, os.path.join(s.out, "results.json")])
        status = status or (1 if guard.returncode != 0 else 0)
    return status


if __name__ == "__main__":
    sys.exit(main())
