#!/usr/bin/env python3
"""Tests of scripts/suite/compare.py (the suite's regression guard) and of the suite's report
writer: each flag condition is provoked on hand-made results and must be reported (exit 1); an
unchanged or improved run must pass (exit 0); the PNG must be a valid PNG.
Usage: suite_compare_test.py SCRIPTS_SUITE_DIR"""
import copy
import json
import os
import struct
import subprocess
import sys
import tempfile
import unittest
import zlib

SUITE = os.path.abspath(sys.argv.pop(1) if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__),
                                                                               "..", "..", "scripts", "suite"))
sys.path.insert(0, SUITE)
import compare  # noqa: E402
import report  # noqa: E402


def run(model, surface, setting, speed, err, holes=0.0, rmse=0.01):
    return {"model": model, "surface": surface, "setting": setting, "rays_per_s": speed, "ns_per_ray": 1e9 / speed,
            "hit_error_mean": err, "hit_error_p99": 3 * err, "hit_error_max": 9 * err, "hole_rate": holes,
            "false_hit_rate": 0.0, "image_rmse": rmse, "normal_error_deg": 1.0, "points": 100000,
            "prep_seconds": 1.0, "prep_peak_mb": 50.0, "bytes_per_point": 40.0}


BASE = {"runs": [run("sphere_100k", "splats", "X32_lc2", 2e6, 1e-4),
                 run("sphere_100k", "iso", "L8_q8_r2", 5e5, 2e-4),
                 run("sphere_100k", "mls", "k4", 1e6, 5e-5)]}


def by_key(results):
    return {compare.key(r): r for r in results["runs"]}


class CompareTest(unittest.TestCase):
    def flags(self, new, **kw):
        return compare.compare(by_key(BASE), by_key(new), **kw)

    def test_identical_runs_pass(self):
        self.assertEqual(self.flags(copy.deepcopy(BASE)), [])

    def test_machine_twice_as_slow_passes_as_ratios_but_not_absolute(self):
        new = copy.deepcopy(BASE)
        for r in new["runs"]:
            r["rays_per_s"] /= 2
        self.assertEqual(self.flags(new), [])
        self.assertEqual(len(self.flags(new, absolute=True)), 3)

    def test_one_surface_slower_by_more_than_ten_percent_is_flagged(self):
        new = copy.deepcopy(BASE)
        new["runs"][1]["rays_per_s"] *= 0.85
        f = self.flags(new)
        self.assertEqual(len(f), 1)
        self.assertIn("iso", f[0])
        self.assertIn("slower", f[0])

    def test_five_percent_slower_passes(self):
        new = copy.deepcopy(BASE)
        new["runs"][2]["rays_per_s"] *= 0.95
        self.assertEqual(self.flags(new), [])

    def test_any_error_increase_is_flagged(self):
        for field in compare.ERRORS:
            if field not in BASE["runs"][2]:
                continue  # a fidelity figure: test_fidelity_runs_are_guarded
            new = copy.deepcopy(BASE)
            new["runs"][2][field] = new["runs"][2][field] * 1.001 + 1e-12
            f = self.flags(new)
            self.assertEqual(len(f), 1, field)
            self.assertIn(field, f[0])

    def test_fidelity_runs_are_guarded(self):
        # issue 15's prt-fidelity rows, read from results.json's "fidelity" list like the runs
        fid = {"model": "bunny_10_scans", "surface": "splats", "setting": "default", "rays_per_s": 3e6,
               "hole_rate": 1e-4, "false_hit_rate": 4e-3, "depth_error_spacings": 0.18, "normal_error_deg": 2.6}
        with tempfile.TemporaryDirectory() as d:
            def load(runs, fidelity):
                path = os.path.join(d, "r.json")
                with open(path, "w") as f:
                    json.dump({"runs": runs, "fidelity": fidelity}, f)
                return compare.load(path)
            base = load(BASE["runs"], [fid])
            self.assertEqual(compare.compare(base, load(BASE["runs"], [fid])), [])
            worse = dict(fid, depth_error_spacings=0.2)
            f = compare.compare(base, load(BASE["runs"], [worse]))
            self.assertEqual(len(f), 1)
            self.assertIn("fidelity:bunny_10_scans/splats/default", f[0])
            self.assertIn("depth_error_spacings", f[0])
            # the anchor stays the first splat run of the runs: a faster fidelity run moves nothing
            faster = dict(fid, rays_per_s=9e6)
            self.assertEqual(compare.compare(base, load(BASE["runs"], [faster])), [])
            self.assertTrue(any("missing" in x for x in compare.compare(base, load(BASE["runs"], []))))

    def test_missing_run_and_nan_are_flagged(self):
        new = copy.deepcopy(BASE)
        del new["runs"][2]
        self.assertTrue(any("missing" in x for x in self.flags(new)))
        new = copy.deepcopy(BASE)
        new["runs"][1]["hit_error_mean"] = float("nan")
        self.assertTrue(any("nan" in x for x in self.flags(new)))

    def test_command_line_exit_status(self):
        with tempfile.TemporaryDirectory() as d:
            a, b = os.path.join(d, "a.json"), os.path.join(d, "b.json")
            json.dump(BASE, open(a, "w"))
            json.dump(BASE, open(b, "w"))
            script = os.path.join(SUITE, "compare.py")
            self.assertEqual(subprocess.run([sys.executable, script, a, b], capture_output=True).returncode, 0)
            worse = copy.deepcopy(BASE)
            worse["runs"][0]["hole_rate"] = 0.01
            json.dump(worse, open(b, "w"))
            r = subprocess.run([sys.executable, script, a, b], capture_output=True, text=True)
            self.assertEqual(r.returncode, 1)
            self.assertIn("hole_rate", r.stdout)
            open(b, "w").write("{not json")
            self.assertEqual(subprocess.run([sys.executable, script, a, b], capture_output=True).returncode, 2)


class ReportTest(unittest.TestCase):
    def test_pareto_front(self):
        pts = [(1, 5), (2, 3), (3, 4), (4, 1), (5, 1)]
        self.assertEqual(report.pareto_front(pts), [0, 1, 3])

    def test_reports_are_written_and_png_is_valid(self):
        with tempfile.TemporaryDirectory() as d:
            result = {"meta": {"quick": True, "gpu": False, "started": "now", "git": "x", "host": "h", "cpus": 2,
                               "seconds": 1.0}, "runs": BASE["runs"], "prep": {"sphere_100k": {
                                   "radii": {"seconds": 0.5, "peak_mb": 30}}}, "bench": [], "failures": []}
            report.write_all(d, result)
            for f in ("results.json", "results.csv", "RESULTS.md", "pareto.png"):
                self.assertTrue(os.path.exists(os.path.join(d, f)), f)
            data = open(os.path.join(d, "pareto.png"), "rb").read()
            self.assertEqual(data[:8], b"\x89PNG\r\n\x1a\n")
            w, h = struct.unpack(">II", data[16:24])
            idat = data[data.index(b"IDAT") + 4:data.index(b"IEND") - 8]
            raw = zlib.decompress(idat)
            self.assertEqual(len(raw), h * (1 + 3 * w))
            # not blank: some pixels of the surface colors are drawn
            self.assertIn(bytes(report.SURFACE_COLORS["iso"]), raw)
            md = open(os.path.join(d, "RESULTS.md")).read()
            self.assertIn("| sphere_100k | iso | L8_q8_r2 |", md)


if __name__ == "__main__":
    unittest.main()
