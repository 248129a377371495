#!/usr/bin/env python3
"""Regression guard of the speed/accuracy suite: compares a new results.json with a baseline.

  scripts/suite/compare.py BASELINE NEW [--slowdown 0.10] [--absolute] [--anchor MODEL/SURFACE/SETTING]

Runs are matched by (model, surface, setting). Flagged (exit status 1):
  - a slowdown over --slowdown (default 10%) in CPU rays/s (of the fastest timed run of each
    setting where recorded: interference on a shared machine only slows runs down). By default speeds are compared as
    ratios measured within one run: each run's rays/s divided by the rays/s of the anchor run of
    the same results file (the first splat run unless --anchor names one), so a machine that is
    busier or slower as a whole does not read as a regression; --absolute compares raw rays/s;
  - any increase of an error figure (hit error mean/p99/max, hole rate, false-hit rate, image
    RMSE, normal error; the fidelity runs' depth error too), beyond --error-tolerance (default
    1e-9 relative: output rounding);
  - a run present in the baseline and missing (or failed) in the new results;
  - a non-finite figure.
Prints one line per flag and a summary; exit 0 when nothing is flagged, 2 on unreadable input.
"""
import argparse
import json
import math
import sys

ERRORS = ["hit_error_mean", "hit_error_p99", "hit_error_max", "hole_rate", "false_hit_rate", "image_rmse",
          "normal_error_deg", "depth_error_spacings"]


def key(r):
    return "%s/%s/%s" % (r["model"], r["surface"], r["setting"])


def load(path):
    try:
        with open(path) as f:
            j = json.load(f)
        runs = {key(r): r for r in j["runs"]}
        # issue 15's fidelity runs: the same checks (speed over the anchor, every error figure)
        runs.update({"fidelity:" + key(r): r for r in j.get("fidelity", [])})
        return runs
    except (OSError, ValueError, KeyError, TypeError) as e:
        print("compare.py: %s: not a suite results.json (%s)" % (path, e), file=sys.stderr)
        sys.exit(2)


def speed(r):
    """rays/s of the least disturbed timed run when recorded (a shared machine only ever slows a run
    down), else the median."""
    return r.get("rays_per_s_best") or r.get("rays_per_s")


def anchor_speed(runs, name):
    if name:
        r = runs.get(name)
        return speed(r) if r else None
    for k in sorted(runs):
        if not k.startswith("fidelity:") and runs[k]["surface"] == "splats" and speed(runs[k]):
            return speed(runs[k])
    return None


def compare(base, new, slowdown=0.10, absolute=False, anchor=None, tol=1e-9):
    """Returns the list of flag messages."""
    flags = []
    ab, an = anchor_speed(base, anchor), anchor_speed(new, anchor)
    if not absolute and (not ab or not an):
        flags.append("anchor run %s missing: cannot normalize speeds (use --absolute)" % (anchor or "(first splats)"))
        return flags
    for k, b in sorted(base.items()):
        n = new.get(k)
        if n is None:
            flags.append("%s: missing from the new results" % k)
            continue
        for f in ["rays_per_s"] + ERRORS:
            v = n.get(f)
            if v is not None and isinstance(v, float) and not math.isfinite(v):
                flags.append("%s: %s is %r" % (k, f, v))
        sb, sn = speed(b), speed(n)
        if sb and sn:
            rb, rn = (sb, sn) if absolute else (sb / ab, sn / an)
            if rn < rb * (1 - slowdown):
                flags.append("%s: %.1f%% slower (%s %.4g -> %.4g)" % (
                    k, 100 * (1 - rn / rb), "rays/s" if absolute else "rays/s over the anchor's", rb, rn))
        for f in ERRORS:
            eb, en = b.get(f), n.get(f)
            if eb is None:
                continue
            if en is None:
                flags.append("%s: %s missing (was %.6g)" % (k, f, eb))
            elif en > eb + tol * max(abs(eb), 1e-300):
                flags.append("%s: %s increased %.6g -> %.6g" % (k, f, eb, en))
    return flags


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("baseline", help="results.json of the baseline run")
    ap.add_argument("new", help="results.json of the run to check")
    ap.add_argument("--slowdown", type=float, default=0.10, help="flagged slowdown fraction (default: 0.10)")
    ap.add_argument("--absolute", action="store_true", help="compare raw rays/s (default: off: ratios to the anchor)")
    ap.add_argument("--anchor", default=None, help="MODEL/SURFACE/SETTING of the anchor run (default: first splats run)")
    ap.add_argument("--error-tolerance", type=float, default=1e-9,
                    help="relative increase of an error figure still accepted (default: 1e-9)")
    a = ap.parse_args()
    flags = compare(load(a.baseline), load(a.new), a.slowdown, a.absolute, a.anchor, a.error_tolerance)
    for f in flags:
        print("FLAG " + f)
    print("compare.py: %d flag(s)" % len(flags))
    return 1 if flags else 0


if __name__ == "__main__":
    sys.exit(main())
