#!/usr/bin/env bash
# Issue 19 on the GPU host (one H200), 2026-12-02, third call: the occupancy of the kernels without
# secondary rays. prt-bench of a tuning build (-DPRT_CUDA_TUNING_KERNELS=ON, built on the dev VM,
# carried as build-ab/new/bin/prt-bench-tune) at each --min-blocks it has for them (0: the default),
# two rounds, 1024x1024, median of 30 frames after 5: prt-bench's room, ISO on the culled room,
# its bricks, the culled 10M-point sphere.
# Usage (repository root): bash preprocess/bench/results/h200-2026-12-02-issue19-kernels/gpu-k4.sh
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/k4.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; t0=$SECONDS
new=$PWD/build-ab/new/bin; w=/tmp/k4; rm -rf $w; mkdir -p $w
q=--quiet
$new/prt-bench --save-pool $w/room.pool --frames 1 --warmup 0 --scenarios primary $q > /dev/null
$new/prt-cull $w/room.pool -o $w/culled.pool $q
$new/prt-iso $w/culled.pool -o $w/surf.pool $q
$new/prt-bricks $w/culled.pool -o $w/bricked.pool --keep-float $q
$new/prt-synth sphere -n 10000000 -o $w/s10.pool $q && $new/prt-radii $w/s10.pool -o $w/s10.pool --backend cuda $q \
  && $new/prt-octree $w/s10.pool -o $w/s10.pool $q && $new/prt-cull $w/s10.pool -o $w/s10.pool $q || echo "sphere failed"
echo "pools done $((SECONDS - t0)) s"
bench() {  # bench LABEL BLOCKS ARGS...
  local label=$1 b=$2; shift 2
  $new/prt-bench-tune --backend cuda --min-blocks $b --frames 30 --warmup 5 --json $w/b.json "$@" > /dev/null 2> $w/err.txt \
    || { echo "$label $b failed: $(tail -2 $w/err.txt)"; return; }
  python3 - "$label" "$b" $w/b.json <<'PY'
import json, sys
j = json.load(open(sys.argv[3]))
print(sys.argv[1].ljust(9), ('blocks ' + sys.argv[2]).ljust(9), ' '.join('%s %.3f' % (x['name'], x['grays_per_s']) for x in j['scenarios']), flush=True)
PY
}
cam="--eye 0,0,3 --look-at 0,0,0 --up 0,1,0 --fov 45"
for r in 1 2; do
  for b in 0 2 3 5; do bench default $b --scenarios primary,shadow; done
  for b in 0 2 3 5; do bench iso $b $w/surf.pool --surface iso --scenarios primary,shadow; done
  for b in 0 2 4; do bench bricks $b $w/bricked.pool --bricks --scenarios primary,shadow; done
  for b in 0 3 5; do bench sphere10m $b $w/s10.pool $cam --scenarios primary,shadow; done
  echo "round $r done $((SECONDS - t0)) s"
done
echo "ALL_DONE $((SECONDS - t0)) s"
