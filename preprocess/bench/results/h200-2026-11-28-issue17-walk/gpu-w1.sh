#!/bin/bash
# Issue 17: the bricked walk's descent as one loop body (top tree, resident brick, missing brick's
# prefix), the brick's counts and leaf-bounds start read once at brick entry (BrickCursor), the
# header read only for leaves whose splats are read. Bench against the float octree on the culled
# 1M sphere and room (direct bricks), two interleaved rounds; ncu per-source-line instructions of
# the room's primary frame (float and bricks); images; then the GPU tests.
set -uo pipefail
OUT=${OUT:-/tmp/out}; mkdir -p "$OUT"; exec > >(tee "$OUT/w1.txt") 2>&1
nvidia-smi --query-gpu=name,clocks.sm,clocks.max.sm --format=csv,noheader
F="-DCMAKE_PREFIX_PATH=$PWD/.device-deps/usr -DPRT_WITH_PCL=OFF -DPRT_WITH_OPENMESH=OFF -DPRT_WITH_OIIO=OFF -DPRT_WITH_PYTHON=OFF -DPRT_WITH_GLFW=OFF -DCMAKE_BUILD_TYPE=Release"
T="prt-bench prt-synth prt-radii prt-octree prt-cull prt-bricks prt-play"
t0=$SECONDS
cmake -S . -B build-dev $F >/tmp/c.txt 2>&1 && cmake --build build-dev -j16 --target $T >/tmp/b.txt 2>&1 || { echo "BUILD FAIL"; grep -E "error" /tmp/b.txt | head -20; exit 1; }
echo "built in $((SECONDS - t0)) s"
( cmake --build build-dev -j16 --target prt_runtime_gpu_tests prt_stability_gpu_tests prt_brick_stream_gpu_tests prt_iso_gpu_tests prt_patches_gpu_tests prt_cull_gpu_tests >/tmp/b2.txt 2>&1 || { grep -E "error" /tmp/b2.txt | head -20; } ) & tests_pid=$!
w=/tmp/w; mkdir -p $w; bin=build-dev/bin
for shape in sphere room; do
  [ -f $w/$shape.pool ] || { $bin/prt-synth $shape -n 1000000 -o $w/$shape.pool --quiet && $bin/prt-radii $w/$shape.pool -o $w/$shape.pool --quiet \
    && $bin/prt-octree $w/$shape.pool -o $w/$shape.pool --quiet && $bin/prt-cull $w/$shape.pool -o $w/$shape.pool --quiet || echo "pool $shape failed"; }
  [ -f $w/$shape-smaller.pool ] || $bin/prt-bricks $w/$shape.pool -o $w/$shape-smaller.pool --keep-float --keep-points --quiet || echo "bricks $shape failed"
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
  for mode in float bricks; do
    extra="--bricks"; [ $mode = float ] && extra=""
    $bin/prt-bench --backend cuda $w/$shape-smaller.pool $cam $extra --scenarios primary,shadow,reflect4,full4 --frames 50 --warmup 10 --quiet --json $w/b.json >/dev/null 2>$w/be.txt || { echo "$shape $mode failed"; tail -2 $w/be.txt; continue; }
    summ "$shape $mode r$rep" $w/b.json
  done
done; done
echo "bench at $((SECONDS - t0)) s"
for shape in sphere room; do
  $bin/prt-play $w/$shape-smaller.pool --bricks --headless --backend cuda --width 512 --height 512 --max-bounces 4 --out $w/img-$shape.ppm -q >/tmp/p.txt 2>&1 || tail -2 /tmp/p.txt
done
sha1sum $w/img-*.ppm
NCU=/usr/local/cuda/bin/ncu
$NCU --help 2>&1 | grep -A4 -E "print-source|--page" | head -30
for mode in float bricks; do
  extra="--bricks"; [ $mode = float ] && extra=""
  $NCU --section SourceCounters --section LaunchStats --import-source yes -k regex:'render' --launch-skip 3 --launch-count 1 -f -o /tmp/src-$mode $bin/prt-bench --backend cuda $w/room-smaller.pool $extra --scenarios primary --frames 1 --warmup 3 -q >/tmp/ncu-$mode.log 2>&1
  echo "ncu $mode rc $?"; tail -3 /tmp/ncu-$mode.log
  $NCU -i /tmp/src-$mode.ncu-rep --page source --csv --print-source cuda > /tmp/src-$mode.csv 2>/tmp/srcerr.txt || { cat /tmp/srcerr.txt | head -5; $NCU -i /tmp/src-$mode.ncu-rep --page source --csv > /tmp/src-$mode.csv 2>>/tmp/srcerr.txt; }
  head -c 600 /tmp/src-$mode.csv; echo
  gzip -c /tmp/src-$mode.csv > $OUT/src-$mode.csv.gz
  $NCU -i /tmp/src-$mode.ncu-rep --page details --csv > $OUT/details-$mode.csv 2>/dev/null
done
echo "ncu at $((SECONDS - t0)) s"
wait $tests_pid
(cd build-dev && ctest -L gpu -E "Window|python|Photons|LightMap|MlsGpu" --timeout 200 --output-on-failure > $OUT/ctest-w1.txt 2>&1; grep -E "tests passed|Failed|FAILED|Not Run|\*\*\*" $OUT/ctest-w1.txt | head -30)
echo "ALL_DONE $((SECONDS - t0)) s"
