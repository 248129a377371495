#!/usr/bin/env bash
# Issue 17, 2026-12-05 (fifth session): why the 500M room's count and bounds passes vary from run to
# run on the GPU host. new2 (main 9efa296's prt-bricks) twice, /proc/vmstat and /proc/meminfo
# sampled every 0.5 s through each run (vmlog.py); the first run's progress lines time-stamped
# (stamp.py) to place the time outside the radii and the build (opening the input, writing the pool).
NAME=e3 TARS="part.tar.xz"
here=$(cd "$(dirname "$0")" && pwd)
. "$here/../h100-2026-12-05-issue17-radii-neighbours/lib500.sh"
p=/tmp/ab/part; x=$p
cat /sys/fs/cgroup/memory.max 2>/dev/null; cat /proc/self/cgroup; grep -E "MemTotal|MemFree|Cached" /proc/meminfo
cat /sys/kernel/mm/transparent_hugepage/enabled /sys/kernel/mm/transparent_hugepage/defrag; sysctl vm.dirty_ratio vm.dirty_background_ratio 2>/dev/null
[ -f $w/s.pool ] || synth
python3 $here/vmlog.py $out/vm-a.txt & vp=$!
/usr/bin/time -f "%e s wall, %U s user, %S s sys, peak RSS %M KB" $p/new2-bricks $w/s.pool -o $w/b-e3a.pool --memory 12G \
  --stats-json $out/bricks500-e3a.json 2>&1 | python3 $here/stamp.py
kill $vp; sum e3a
python3 $here/vmlog.py $out/vm-b.txt & vp=$!
line e3b $p/new2-bricks; kill $vp; sum e3b
compare e3a e3b
