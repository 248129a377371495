#!/usr/bin/env bash
# Issue 17, 2026-12-05 (fifth session): new4 = new2 + the count pass keeping no per-point cell (the
# scatter places each point again) + the pool reader hashing the sections at once, against new2
# (main 9efa296), on the 500M room; /proc/vmstat sampled through each run (vmlog.py, now with the
# compaction counters), new4's first run's progress time-stamped (stamp.py).
NAME=e4 TARS="part.tar.xz"
here=$(cd "$(dirname "$0")" && pwd)
. "$here/../h100-2026-12-05-issue17-radii-neighbours/lib500.sh"
p=/tmp/ab/part; x=$p
[ -f $w/s.pool ] || synth
python3 $here/vmlog.py $out/vm-e4a.txt & vp=$!
/usr/bin/time -f "%e s wall, %U s user, %S s sys, peak RSS %M KB" $p/new4-bricks $w/s.pool -o $w/b-new4a.pool --memory 12G \
  --stats-json $out/bricks500-new4a.json 2>&1 | python3 $here/stamp.py
kill $vp; python3 -c "
import json; s = json.load(open('$out/bricks500-new4a.json')); print('new4a passes', s['partition_passes'], 'radii', s['radii']['seconds'], 'build', s['build_seconds'], 'total', s['total_seconds'])"
sum new4a
python3 $here/vmlog.py $out/vm-e4b.txt & vp=$!
line new2e $p/new2-bricks; kill $vp; sum new2e
python3 $here/vmlog.py $out/vm-e4c.txt & vp=$!
line new4b $p/new4-bricks; kill $vp; sum new4b
if (( SECONDS - t0 < 430 )); then line new2f $p/new2-bricks; sum new2f; compare new2e new4a new4b new2f
else compare new2e new4a new4b; fi
