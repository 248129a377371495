#!/bin/bash
# Issue 17: the tracer's brick decode without divisions (octahedral codes times 1/511, the position
# step divided once per brick) and without normalizing the normal of every tested splat (only the
# blended ones): bench as gpu-r1.sh on fresh pools, images of both layouts, ncu, then the GPU tests.
set -uo pipefail
OUT=${OUT:-/tmp/out}; mkdir -p "$OUT"; exec > >(tee "$OUT/r3.txt") 2>&1
nvidia-smi --query-gpu=name,clocks.sm,clocks.max.sm --format=csv,noheader
F="-DCMAKE_PREFIX_PATH=$PWD/.device-deps/usr -DPRT_WITH_PCL=OFF -DPRT_WITH_OPENMESH=OFF -DPRT_WITH_OIIO=OFF -DPRT_WITH_PYTHON=OFF -DPRT_WITH_GLFW=OFF -DCMAKE_BUILD_TYPE=Release"
T="prt-bench prt-synth prt-radii prt-octree prt-cull prt-bricks prt-play"
t0=$SECONDS
cmake -S . -B build-dev $F >/tmp/c.txt 2>&1 && cmake --build build-dev -j16 --target $T >/tmp/b.txt 2>&1 || { echo "BUILD FAIL"; grep -E "error" /tmp/b.txt | head -20; exit 1; }
echo "built in $((SECONDS - t0)) s"
w=/tmp/w; mkdir -p $w; bin=build-dev/bin
for shape in sphere room; do
  [ -f $w/$shape.pool ] || { $bin/prt-synth $shape -n 1000000 -o $w/$shape.pool --quiet && $bin/prt-radii $w/$shape.pool -o $w/$shape.pool --quiet \
    && $bin/prt-octree $w/$shape.pool -o $w/$shape.pool --quiet && $bin/prt-cull $w/$shape.pool -o $w/$shape.pool --quiet || echo "pool $shape failed"; }
  for d in never smaller; do
    $bin/prt-bricks $w/$shape.pool -o $w/$shape-$d.pool --direct $d --keep-float --keep-points --stats-json $OUT/bricks3-$shape-$d.json 2>&1 | grep -E "codec error" || echo "bricks $shape $d failed"
  done
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
  for mode in float never smaller; do
    pool=$w/$shape-$mode.pool; extra="--bricks"
    [ $mode = float ] && { pool=$w/$shape-smaller.pool; extra=""; }
    $bin/prt-bench --backend cuda $pool $cam $extra --scenarios primary,shadow,reflect4,full4 --frames 50 --warmup 10 --quiet --json $w/b.json >/dev/null 2>$w/be.txt || { echo "$shape $mode failed"; tail -2 $w/be.txt; continue; }
    cp $w/b.json $OUT/r3-$shape-$mode-r$rep.json
    summ "$shape $mode r$rep" $w/b.json
  done
done; done
for shape in sphere room; do for d in never smaller; do
  $bin/prt-play $w/$shape-$d.pool --bricks --headless --backend cuda --width 512 --height 512 --out /tmp/img-$shape-$d.ppm -q >/tmp/p.txt 2>&1 || tail -2 /tmp/p.txt
done; done
sha1sum /tmp/img-*.ppm
NCU=/usr/local/cuda/bin/ncu
M=gpu__time_duration.sum,smsp__inst_executed.sum,smsp__thread_inst_executed.sum,launch__registers_per_thread,launch__occupancy_limit_registers,sm__warps_active.avg.pct_of_peak_sustained_active,smsp__sass_inst_executed_op_branch.sum,smsp__inst_executed_pipe_xu.sum,smsp__issue_active.avg.pct_of_peak_sustained_active,smsp__inst_executed_op_global_ld.sum,smsp__inst_executed_op_local_ld.sum
for mode in float smaller; do
  extra="--bricks"; [ $mode = float ] && extra=""
  $NCU --metrics $M -k regex:'render' --launch-skip 3 --launch-count 1 --csv --print-units base $bin/prt-bench --backend cuda $w/room-smaller.pool $extra --scenarios primary --frames 1 --warmup 3 -q >$OUT/ncu3-room-$mode.csv 2>/dev/null
  grep -E "inst_executed.sum|registers_per|time_duration" $OUT/ncu3-room-$mode.csv | awk -F'","' '{print "'$mode'", $(NF-2), $NF}'
done
echo "ncu at $((SECONDS - t0)) s"
cmake --build build-dev -j16 --target prt_runtime_gpu_tests prt_stability_gpu_tests prt_brick_stream_gpu_tests prt_iso_gpu_tests prt_patches_gpu_tests prt_cull_gpu_tests >/tmp/b2.txt 2>&1 || { grep -E "error" /tmp/b2.txt | head -20; }
echo "built tests at $((SECONDS - t0)) s"
(cd build-dev && ctest -L gpu -E "Window|python|Photons|LightMap|MlsGpu" --timeout 200 --output-on-failure > $OUT/ctest3.txt 2>&1; grep -E "tests passed|Failed|FAILED|Not Run|\*\*\*" $OUT/ctest3.txt | head -30)
echo "ALL_DONE $((SECONDS - t0)) s"
