#!/usr/bin/env bash
# Issue 19 (e3): the default build with the splat kernels at 3 blocks per SM (build-ab/k2.tar.xz:
# every GPU test program, prt-bench and the tools, built on the dev VM). Every GPU test program;
# prt-bench's splat scenarios with the defaults (no --min-blocks), each alone, median of 100 frames
# after 10, two rounds; the library's cast kernels (prt-bench-cast, 10M random rays from a sphere of
# radius 3 toward the model's box, rays and outputs on the device) with their splat variant at 4
# (old/libpointrt.so.0) and 3 blocks, alternating.
NAME=e3 TARS="k2.tar.xz"
source preprocess/bench/results/h100-2026-12-05-issue17-radii-neighbours/lib500.sh
source preprocess/bench/results/h100-2026-12-06-issue19-region-axes/alone.sh
x=$kall; q=--quiet; nb=$kall/prt-bench  # al(): alone.sh
gpu_tests
make_pools $x
make_sphere1 $x
echo "pools done $((SECONDS - t0)) s"
sph="--eye 0,0,3 --look-at 0,0,0 --up 0,1,0 --fov 45"; room="--scene preprocess/bench/bench_room.json"
S=primary,shadow,reflect4,full4
for r in 1 2; do
  al "r$r splats, culled room (bench_room.json):" $S $w/croom.pool $room
  al "r$r splats, prt-bench's room:" $S
  al "r$r splats, culled 1M sphere:" primary,shadow,reflect4 $w/cs1.pool $sph
  al "r$r splats, 1M sphere not culled:" primary,shadow $w/s1.pool $sph
  al "r$r splats, culled 10M sphere:" $S $w/cs10.pool $sph
  al "r$r splats, 10M sphere not culled:" primary,shadow $w/s10.pool $sph
  echo "round $r done $((SECONDS - t0)) s"
done
al "ISO, culled 10M sphere:" primary $w/is10.pool $sph --surface iso
python3 - $w <<'PY'
import sys, numpy as np
w = sys.argv[1]
for name, c, h in (("sphere", 0.0, 1.0), ("room", 0.0, 0.5)):
    rng = np.random.default_rng(1); n = 10_000_000
    o = rng.normal(size=(n, 3)).astype(np.float32)
    o *= (3 * h * 3 ** 0.5) / np.linalg.norm(o, axis=1, keepdims=True)
    t = ((rng.random((n, 3)) * 2 - 1) * h).astype(np.float32)
    rec = np.empty((n, 6), np.float32); rec[:, :3] = o; rec[:, 3:] = t - o
    rec.tofile(f"{w}/rays-{name}.f32")
PY
for r in 1 2; do
  for pool in cs1 croom cs10; do
    ray=$w/rays-sphere.f32; [ $pool = croom ] && ray=$w/rays-room.f32
    for v in old new; do
      lib=$kall; [ $v = old ] && lib=$kall/old
      LD_LIBRARY_PATH=$lib $kall/prt-bench-cast $w/$pool.pool $ray --backend cuda --repeat 5 --device > $w/cast.txt 2>&1
      echo "r$r cast $pool $v: $(python3 -c "
import re, sys; t = open('$w/cast.txt').read(); k = [float(m) for m in re.findall(r'kernel ([0-9.]+) ms', t)]
b = re.findall(r'best: ([0-9.]+)', t); print('best %s Mrays/s, kernel min %.3f ms' % (b[-1], min(k)) if k and b else t.strip()[-300:])")"
    done
  done
done
echo "ALL_DONE $((SECONDS - t0)) s"
