#!/bin/bash
# Issue 17: w3 made primary rays faster (room 1.35 against 1.26 Grays/s) but shadow rays much slower
# (0.85 against 1.17) with the same leaves and splat tests per ray. Three builds of this tree side by
# side: A = w3 (the descent's inner loop the float descent's), B = A with w1's one-body descent
# (PRT_BRICK_DESCENT_ONE_BODY=1), C = B with the splat records read by generic loads
# (PRT_BRICK_NO_LDG=1). Bench each against the float octree; ncu source page of A's and B's room
# shadow frame; B's GPU tests.
set -uo pipefail
OUT=${OUT:-/tmp/out}; mkdir -p "$OUT"; exec > >(tee "$OUT/w4.txt") 2>&1
nvidia-smi --query-gpu=name,clocks.sm,clocks.max.sm --format=csv,noheader
F="-DCMAKE_PREFIX_PATH=$PWD/.device-deps/usr -DPRT_WITH_PCL=OFF -DPRT_WITH_OPENMESH=OFF -DPRT_WITH_OIIO=OFF -DPRT_WITH_PYTHON=OFF -DPRT_WITH_GLFW=OFF -DCMAKE_BUILD_TYPE=Release"
TESTS="prt_runtime_gpu_tests prt_stability_gpu_tests prt_brick_stream_gpu_tests prt_iso_gpu_tests prt_patches_gpu_tests prt_cull_gpu_tests"
t0=$SECONDS
( cmake -S . -B build-a $F >/tmp/ca.txt 2>&1 && cmake --build build-a -j6 --target prt-bench prt-synth prt-radii prt-octree prt-cull prt-bricks prt-play >/tmp/ba.txt 2>&1 || echo "BUILD A FAIL" ) & pa=$!
( cmake -S . -B build-b $F -DCMAKE_CUDA_FLAGS="-DPRT_BRICK_DESCENT_ONE_BODY=1" -DCMAKE_CXX_FLAGS="-DPRT_BRICK_DESCENT_ONE_BODY=1" >/tmp/cb.txt 2>&1 && cmake --build build-b -j8 --target prt-bench prt-play $TESTS >/tmp/bb.txt 2>&1 || echo "BUILD B FAIL" ) & pb=$!
( cmake -S . -B build-c $F -DCMAKE_CUDA_FLAGS="-DPRT_BRICK_DESCENT_ONE_BODY=1 -DPRT_BRICK_NO_LDG=1" >/tmp/cc.txt 2>&1 && cmake --build build-c -j4 --target prt-bench >/tmp/bc.txt 2>&1 || echo "BUILD C FAIL" ) & pc=$!
while [ ! -x build-a/bin/prt-bricks ] || [ ! -x build-b/bin/prt-bench ] || [ ! -x build-c/bin/prt-bench ]; do sleep 5; [ $((SECONDS - t0)) -gt 420 ] && { echo "builds too slow"; grep -h error /tmp/b?.txt | head; break; }; done
echo "benches built in $((SECONDS - t0)) s"
w=/tmp/w; mkdir -p $w; bin=build-a/bin
for shape in sphere room; do
  $bin/prt-synth $shape -n 1000000 -o $w/$shape.pool --quiet && $bin/prt-radii $w/$shape.pool -o $w/$shape.pool --quiet \
    && $bin/prt-octree $w/$shape.pool -o $w/$shape.pool --quiet && $bin/prt-cull $w/$shape.pool -o $w/$shape.pool --quiet || echo "pool $shape failed"
  $bin/prt-bricks $w/$shape.pool -o $w/$shape-smaller.pool --keep-float --keep-points --quiet || echo "bricks $shape failed"
done
echo "pools at $((SECONDS - t0)) s"
summ() { python3 - "$1" "$2" <<'PY'
import json, sys
j = json.load(open(sys.argv[2]))
print(sys.argv[1].ljust(22), ' '.join('%s %.3f (%.2f, %.2f)' % (x['name'], x['grays_per_s'], x.get('leaves_per_ray', 0), x.get('splat_tests_per_ray', 0)) for x in j['scenarios']))
PY
}
for rep in 1 2; do for shape in sphere room; do
  cam=""; [ $shape = sphere ] && cam="--eye 0,0,3 --look-at 0,0,0 --up 0,1,0 --fov 45"
  for mode in float A B C; do
    extra="--bricks"; b=build-$(echo $mode | tr ABC abc)/bin
    [ $mode = float ] && { extra=""; b=build-a/bin; }
    $b/prt-bench --backend cuda $w/$shape-smaller.pool $cam $extra --scenarios primary,shadow,reflect4,full4 --frames 50 --warmup 10 --quiet --json $w/b.json >/dev/null 2>$w/be.txt || { echo "$shape $mode failed"; tail -2 $w/be.txt; continue; }
    summ "$shape $mode r$rep" $w/b.json
  done
done; done
echo "bench at $((SECONDS - t0)) s"
NCU=/usr/local/cuda/bin/ncu
for mode in A B; do
  b=build-$(echo $mode | tr AB ab)/bin
  $NCU --section SourceCounters --import-source yes -k regex:'render' --launch-skip 3 --launch-count 1 -f -o /tmp/src-$mode $b/prt-bench --backend cuda $w/room-smaller.pool --bricks --scenarios shadow --frames 1 --warmup 3 -q >/tmp/ncu-$mode.log 2>&1
  echo "ncu $mode rc $?"
  $NCU -i /tmp/src-$mode.ncu-rep --page source --csv --print-source cuda,sass 2>/dev/null | gzip -c > $OUT/sass-shadow-$mode.csv.gz
done
echo "ncu at $((SECONDS - t0)) s"
wait $pa $pb $pc
(cd build-b && ctest -L gpu -E "Window|python|Photons|LightMap|MlsGpu" --timeout 200 --output-on-failure > $OUT/ctest-w4b.txt 2>&1; grep -E "tests passed|Failed|FAILED|Not Run|\*\*\*" $OUT/ctest-w4b.txt | head -30)
echo "ALL_DONE $((SECONDS - t0)) s"
