#!/usr/bin/env bash
# Issue 17, 2026-12-05 (sixth session): what bounds the 500M room's cells: is the GPU busy all
# through them? Main 94699bb's prt-bricks (build-ab/diag.tar.xz, bin/), the 500M room from points
# (--memory 12G), with 16 cell workers (the default) then 8; through each run nvidia-smi samples the
# GPU's load every 200 ms and load.py the CPU's (user, system, idle, steal) every 250 ms, and the
# progress lines are time-stamped on the same clock.
NAME=f1 TARS="diag.tar.xz"
here=$(cd "$(dirname "$0")" && pwd)
. "$here/../h100-2026-12-05-issue17-radii-neighbours/lib500.sh"
ls /usr/local/cuda/bin | tr '\n' ' '; echo; nproc; grep -E "MemTotal|MemFree" /proc/meminfo
[ -f $w/s.pool ] || synth
run() {  # label [options]
  export T0=$(date +%s.%N)
  nvidia-smi --query-gpu=timestamp,utilization.gpu,utilization.memory,memory.used,power.draw,clocks.sm --format=csv,noheader -lms 200 > $out/gpu-$1.csv & local gp=$!
  python3 $here/load.py $out/cpu-$1.txt & local cp=$!
  /usr/bin/time -f "%e s wall, %U s user, %S s sys, peak RSS %M KB" $x/prt-bricks $w/s.pool -o $w/b-$1.pool --memory 12G \
    --stats-json $out/bricks500-$1.json ${2:-} 2>&1 | python3 $here/stamp.py > $out/stamps-$1.txt
  kill $gp $cp; tail -3 $out/stamps-$1.txt; sum $1
  python3 -c "
import json; s = json.load(open('$out/bricks500-$1.json'))
print('$1: total %.1f s, build %.1f s; summed octree %.1f bricks %.1f; passes %s' % (s['total_seconds'], s['build_seconds'], s['seconds']['octree'], s['seconds']['bricks'], s.get('partition_passes')))"
}
run w16
run w8 "--cell-workers 8"
compare w16 w8
