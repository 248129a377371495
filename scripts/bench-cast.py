#!/usr/bin/env python3
"""Rays per second of the library (issue 18): the same random rays cast at a pool through the
Python module (numpy arrays, or torch CUDA tensors with --torch) and through the C++ API
(prt-bench-cast), best of --repeat runs each, every output field computed by both.

Rays: origins uniform on a sphere of radius 3 around the pool's centre (in units of its bounding
radius), directions toward points uniform in its bounding cube, so most rays hit a closed model.
Without --pool a 1M-point unit sphere is built in --work (prt-synth, prt-radii, prt-octree).

    PYTHONPATH=build/python python3 scripts/bench-cast.py --rays 10000000 --backend cuda --torch
"""
import argparse
import os
import subprocess
import sys
import tempfile
import time

import numpy as np


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--pool", help="pool to cast at (default: a 1M-point sphere built in --work)")
    ap.add_argument("--points", type=int, default=1000000, help="points of the built sphere (default 1000000)")
    ap.add_argument("--rays", type=int, default=10000000, help="rays per batch (default 10000000)")
    ap.add_argument("--backend", default="auto", help="cpu, cuda or auto (default auto)")
    ap.add_argument("--repeat", type=int, default=3, help="runs of each path; the best counts (default 3)")
    ap.add_argument("--torch", action="store_true", help="also cast torch CUDA tensors (no copies)")
    ap.add_argument("--bin", default=None, help="folder of prt-* binaries (default: build/bin)")
    ap.add_argument("--work", default=None, help="folder for the built pool and the ray file (default: a temp folder)")
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args()

    import pointrt

    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    bin_dir = a.bin or os.path.join(root, "build", "bin")
    work = a.work or tempfile.mkdtemp(prefix="prt-bench-cast-")
    os.makedirs(work, exist_ok=True)
    pool = a.pool
    if not pool:
        pool = os.path.join(work, "sphere-%d.pool" % a.points)
        if not os.path.exists(pool):
            raw, radii = pool + ".synth", pool + ".radii"
            t0 = time.time()
            subprocess.run([os.path.join(bin_dir, "prt-synth"), "sphere", "-n", str(a.points), "-o", raw, "-q"], check=True)
            subprocess.run([os.path.join(bin_dir, "prt-radii"), raw, "-o", radii, "-q"], check=True)
            subprocess.run([os.path.join(bin_dir, "prt-octree"), radii, "-o", pool, "-q"], check=True)
            os.remove(raw)
            os.remove(radii)
            print("built %s in %.1f s" % (pool, time.time() - t0), file=sys.stderr)

    s = pointrt.open(pool, backend=a.backend)
    info = s.info
    lo, hi = np.array(info["world_min"]), np.array(info["world_max"])
    centre, radius = (lo + hi) / 2, np.linalg.norm(hi - lo) / 2
    rng = np.random.default_rng(a.seed)
    n = a.rays
    o = rng.normal(size=(n, 3)).astype(np.float32)
    o *= (3 * radius) / np.linalg.norm(o, axis=1, keepdims=True)
    o += centre.astype(np.float32)
    target = (centre + (rng.random((n, 3)) * 2 - 1) * (hi - lo) / 2).astype(np.float32)
    rec = np.empty((n, 6), dtype=np.float32)  # the file prt-bench-cast reads: origin, direction
    rec[:, :3] = o
    rec[:, 3:] = target - o
    del o, target
    ray_file = os.path.join(work, "rays.f32")
    rec.tofile(ray_file)
    print("pool %s: %d points, backend %s on %s; %d rays" % (pool, info["points"], info["backend"], info["device"], n))

    # Python, numpy arrays (strided views of the same records, as the C++ side reads them).
    origins, directions = rec[:, :3], rec[:, 3:]
    best = float("inf")
    for _ in range(a.repeat):
        t0 = time.perf_counter()
        h = s.cast(origins, directions)
        dt = time.perf_counter() - t0
        best = min(best, dt)
        print("python: %d rays in %.4f s = %.2f Mrays/s (hits %d)" % (n, dt, n / dt * 1e-6, int(h["hit"].sum())))
    py_rate = n / best
    del h

    torch_rate = None
    if a.torch:
        import torch

        to = torch.as_tensor(rec[:, :3].copy(), device="cuda")
        td = torch.as_tensor(rec[:, 3:].copy(), device="cuda")
        torch.cuda.synchronize()
        tbest = float("inf")
        for _ in range(a.repeat):
            t0 = time.perf_counter()
            h = s.cast(to, td)
            tbest = min(tbest, time.perf_counter() - t0)
        hits = int(torch.as_tensor(h["hit"], device="cuda").sum().item())
        torch_rate = n / tbest
        print("python+torch: best %.4f s = %.2f Mrays/s (hits %d, kernel %.2f ms)" % (tbest, torch_rate * 1e-6, hits, s.last_stats["device_ms"]))

    # The C++ API on the same rays.
    cmd = [os.path.join(bin_dir, "prt-bench-cast"), pool, ray_file, "--backend", a.backend, "--repeat", str(a.repeat)]
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    print(out.rstrip())
    cpp_rate = float(out.strip().splitlines()[-1].split()[2]) * 1e6
    if a.torch:
        out = subprocess.run(cmd + ["--device"], check=True, capture_output=True, text=True).stdout
        print("device arrays: " + out.strip().splitlines()[-1])
    print("python/numpy %.2f Mrays/s, C++ API %.2f Mrays/s: python = %.1f %% of C++" % (py_rate * 1e-6, cpp_rate * 1e-6, 100 * py_rate / cpp_rate))
    if torch_rate:
        print("python/torch %.2f Mrays/s" % (torch_rate * 1e-6))
    if not a.work:
        os.remove(ray_file)


if __name__ == "__main__":
    main()
