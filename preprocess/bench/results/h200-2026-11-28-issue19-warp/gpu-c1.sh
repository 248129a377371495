#!/bin/bash
# Issue 19 / 17: the lanes of a warp test their leaves' splats together (splat.h leaf_hits). Three
# builds side by side: A = the tree before (HEAD, exported to .device-deps/base-src), B = this tree,
# C = this tree with -DPRT_WARP_SPLATS=0 (the loops restructured, each lane testing its own leaf).
# prt-bench of the float octree and the bricks, culled 1M sphere and room, two interleaved rounds;
# images of A and B compared; B's GPU tests.
set -uo pipefail
OUT=${OUT:-/tmp/out}; mkdir -p "$OUT"; exec > >(tee "$OUT/c1.txt") 2>&1
nvidia-smi --query-gpu=name,clocks.sm,clocks.max.sm --format=csv,noheader
F="-DCMAKE_PREFIX_PATH=$PWD/.device-deps/usr -DPRT_WITH_PCL=OFF -DPRT_WITH_OPENMESH=OFF -DPRT_WITH_OIIO=OFF -DPRT_WITH_PYTHON=OFF -DPRT_WITH_GLFW=OFF -DCMAKE_BUILD_TYPE=Release"
TESTS="prt_runtime_gpu_tests prt_stability_gpu_tests prt_brick_stream_gpu_tests prt_iso_gpu_tests prt_patches_gpu_tests prt_cull_gpu_tests"
t0=$SECONDS
( cmake -S .device-deps/base-src -B build-a $F >/tmp/ca.txt 2>&1 && cmake --build build-a -j5 --target prt-bench prt-synth prt-radii prt-octree prt-cull prt-bricks prt-play >/tmp/ba.txt 2>&1 || echo "BUILD A FAIL" ) & pa=$!
( cmake -S . -B build-b $F >/tmp/cb.txt 2>&1 && cmake --build build-b -j8 --target prt-bench prt-play $TESTS >/tmp/bb.txt 2>&1 || echo "BUILD B FAIL" ) & pb=$!
( cmake -S . -B build-c $F -DCMAKE_CUDA_FLAGS="-DPRT_WARP_SPLATS=0" >/tmp/cc.txt 2>&1 && cmake --build build-c -j4 --target prt-bench >/tmp/bc.txt 2>&1 || echo "BUILD C FAIL" ) & pc=$!
while [ ! -x build-a/bin/prt-bricks ] || [ ! -x build-a/bin/prt-bench ] || [ ! -x build-b/bin/prt-bench ] || [ ! -x build-c/bin/prt-bench ]; do sleep 5; [ $((SECONDS - t0)) -gt 400 ] && { echo "builds too slow"; grep -h error /tmp/b?.txt | head; break; }; done
echo "benches built in $((SECONDS - t0)) s"
w=/tmp/w; mkdir -p $w; bin=build-a/bin
for shape in sphere room; do
  $bin/prt-synth $shape -n 1000000 -o $w/$shape.pool --quiet && $bin/prt-radii $w/$shape.pool -o $w/$shape.pool --quiet \
    && $bin/prt-octree $w/$shape.pool -o $w/$shape.pool --quiet && $bin/prt-cull $w/$shape.pool -o $w/$shape.pool --quiet || echo "pool $shape failed"
  $bin/prt-bricks $w/$shape.pool -o $w/$shape-b.pool --keep-float --keep-points --quiet || echo "bricks $shape failed"
done
echo "pools at $((SECONDS - t0)) s"
summ() { python3 - "$1" "$2" <<'PY'
import json, sys
j = json.load(open(sys.argv[2]))
print(sys.argv[1].ljust(24), ' '.join('%s %.3f (%.2f, %.2f)' % (x['name'], x['grays_per_s'], x.get('leaves_per_ray', 0), x.get('splat_tests_per_ray', 0)) for x in j['scenarios']))
PY
}
for rep in 1 2; do for shape in sphere room; do
  cam=""; [ $shape = sphere ] && cam="--eye 0,0,3 --look-at 0,0,0 --up 0,1,0 --fov 45"
  for tree in float bricks; do for build in a b c; do
    extra=""; [ $tree = bricks ] && extra="--bricks"
    build-$build/bin/prt-bench --backend cuda $w/$shape-b.pool $cam $extra --scenarios primary,shadow,reflect4,full4 --frames 50 --warmup 10 --quiet --json $w/b.json >/dev/null 2>$w/be.txt || { echo "$shape $tree $build failed"; tail -2 $w/be.txt; continue; }
    summ "$shape $tree $build r$rep" $w/b.json
  done; done
done; done
echo "bench at $((SECONDS - t0)) s"
for shape in sphere room; do
  cam=""; [ $shape = sphere ] && cam="--eye 0,0,3 --look-at 0,0,0 --up 0,1,0 --fov 45"
  for tree in float bricks; do
    extra=""; [ $tree = bricks ] && extra="--bricks"
    for build in a b; do build-$build/bin/prt-play $w/$shape-b.pool --backend cuda $cam $extra --width 512 --height 512 --max-bounces 4 --out $w/$shape-$tree-$build.pfm --quiet || echo "play $shape $tree $build failed"; done
    python3 - $w/$shape-$tree-a.pfm $w/$shape-$tree-b.pfm "$shape $tree" <<'PY'
import sys, numpy as np
def pfm(p):
    with open(p, 'rb') as f:
        f.readline(); w, h = map(int, f.readline().split()); s = float(f.readline())
        return np.fromfile(f, '<f4' if s < 0 else '>f4').reshape(h, w, 3)
a, b = pfm(sys.argv[1]), pfm(sys.argv[2]); d = np.abs(a - b).max(axis=2)
print('image A vs B %-14s pixels differing %d (> 1/255: %d), max %.3g, NaN %d' % (sys.argv[3], int((d > 0).sum()), int((d > 1 / 255).sum()), float(d.max()), int(np.isnan(b).sum())))
PY
  done
done
wait $pa $pb $pc
(cd build-b && ctest -L gpu -E "Window|python|Photons|LightMap|MlsGpu" --timeout 200 --output-on-failure > $OUT/ctest-c1.txt 2>&1; grep -E "tests passed|Failed|FAILED|Not Run|\*\*\*" $OUT/ctest-c1.txt | head -30)
echo "ALL_DONE $((SECONDS - t0)) s"
