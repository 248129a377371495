#!/usr/bin/env bash
# Issue 17, 2026-12-05 (sixth session): the point records' spill files closed on a thread of their
# own, each part as soon as its cells are built (SpillReleaser), instead of all at once after the
# cells: in gpu-f1.sh's w16 run the build sat 6 s in I/O wait there. cur = main d2ff0f4 (kall/, the
# build records on the GPU), rel = that + the releaser (rel/); the 500M room (--memory 12G)
# alternating cur / rel / cur / rel, each sampled as in gpu-f2.sh; every run's samples and stamps
# come back in f3-runs.tar.gz.
NAME=f3 TARS="diag.tar.xz kall.tar.xz rel.tar.xz"
here=$(cd "$(dirname "$0")" && pwd)
. "$here/../h100-2026-12-05-issue17-radii-neighbours/lib500.sh"
for d in /tmp/wf2 /tmp/wf1; do [ -f $d/s.pool ] && w=$d && break; done  # a warm host keeps its room
[ -f $w/s.pool ] || synth
mkdir -p /tmp/runs
run() {  # label binary
  export T0=$(date +%s.%N)
  nvidia-smi --query-gpu=timestamp,utilization.gpu,utilization.memory,memory.used,power.draw,clocks.sm --format=csv,noheader -lms 200 > /tmp/runs/gpu-$1.csv & local gp=$!
  python3 $here/load.py /tmp/runs/cpu-$1.txt & local cp=$!
  /usr/bin/time -f "%e s wall, %U s user, %S s sys, peak RSS %M KB" $2 $w/s.pool -o $w/b-$1.pool --memory 12G \
    --stats-json /tmp/runs/bricks500-$1.json 2>&1 | python3 $here/stamp.py > /tmp/runs/stamps-$1.txt
  kill $gp $cp; tail -2 /tmp/runs/stamps-$1.txt; sum $1
  python3 -c "
import json; s = json.load(open('/tmp/runs/bricks500-$1.json'))
print('$1: total %.1f s, build %.1f s, radii %.2f s; summed octree %.1f bricks %.1f; passes %s' % (s['total_seconds'], s['build_seconds'], s['radii']['seconds'], s['seconds']['octree'], s['seconds']['bricks'], s.get('partition_passes')))"
}
run cur1 $kall/prt-bricks
run rel1 /tmp/ab/rel/prt-bricks
run cur2 $kall/prt-bricks
run rel2 /tmp/ab/rel/prt-bricks
tar -czf $out/f3-runs.tar.gz -C /tmp/runs .
compare cur1 rel1 cur2 rel2
