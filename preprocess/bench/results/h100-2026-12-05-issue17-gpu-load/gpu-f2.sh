#!/usr/bin/env bash
# Issue 17, 2026-12-05 (sixth session): a cell's build records made on the GPU (the usable points'
# core::make_build_splat in the CPU's Morton order, by a stable radix sort) instead of by the cell
# worker on the CPU. Every GPU test program of the new tree (build-ab/kall.tar.xz, kall/: every tool
# and GPU test built on the dev VM), then the 500M room from points (--memory 12G, 16 cell workers)
# with main 94699bb's prt-bricks (diag.tar.xz, bin/) and the new one alternating, old / new / old /
# new, each sampled as in gpu-f1.sh (GPU load, CPU split, time-stamped progress), sections compared.
NAME=f2 TARS="diag.tar.xz kall.tar.xz"
here=$(cd "$(dirname "$0")" && pwd)
. "$here/../h100-2026-12-05-issue17-radii-neighbours/lib500.sh"
gpu_tests
[ -f /tmp/wf1/s.pool ] && w=/tmp/wf1  # a warm host from gpu-f1.sh keeps its 500M room
[ -f $w/s.pool ] || synth
run() {  # label binary
  export T0=$(date +%s.%N)
  nvidia-smi --query-gpu=timestamp,utilization.gpu,utilization.memory,memory.used,power.draw,clocks.sm --format=csv,noheader -lms 200 > $out/gpu-$1.csv & local gp=$!
  python3 $here/load.py $out/cpu-$1.txt & local cp=$!
  /usr/bin/time -f "%e s wall, %U s user, %S s sys, peak RSS %M KB" $2 $w/s.pool -o $w/b-$1.pool --memory 12G \
    --stats-json $out/bricks500-$1.json 2>&1 | python3 $here/stamp.py > $out/stamps-$1.txt
  kill $gp $cp; tail -2 $out/stamps-$1.txt; sum $1
  python3 -c "
import json; s = json.load(open('$out/bricks500-$1.json'))
print('$1: total %.1f s, build %.1f s; summed octree %.1f bricks %.1f; passes %s' % (s['total_seconds'], s['build_seconds'], s['seconds']['octree'], s['seconds']['bricks'], s.get('partition_passes')))"
}
run old1 $x/prt-bricks
run new1 $kall/prt-bricks
run old2 $x/prt-bricks
run new2 $kall/prt-bricks
compare old1 new1 old2 new2
