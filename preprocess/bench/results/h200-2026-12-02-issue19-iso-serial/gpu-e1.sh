#!/usr/bin/env bash
# Issue 19 on the GPU host (one H200), 2026-12-02: ISO frames with secondary rays (reflect4, full4)
# on an ISO-only kernel with secondary rays at 3, 4 and 5 blocks per SM (exp, PRT_EXP_ISO2=1,
# --min-blocks) against the general kernel they run today (base; exp without the variable is the
# same code path). Culled 1M room's ISO, 1024x1024, median of 30 frames after 5; then Nsight
# Compute on one full4 frame's kernel of each.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/e1.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; t0=$SECONDS
x=$PWD/build-ab/exp; c=$PWD/build-ab/cur; w=/tmp/e1; mkdir -p $w; q=--quiet
$x/prt-bench --save-pool $w/room.pool --frames 1 --warmup 0 --scenarios primary $q > /dev/null
$c/prt-cull $w/room.pool -o $w/culled.pool $q && $c/prt-iso $w/culled.pool -o $w/surf.pool $q
echo "pools done $((SECONDS - t0)) s"
bench() {  # bench LABEL BIN ARGS...
  local label=$1 bin=$2; shift 2
  $bin --backend cuda --frames 30 --warmup 5 --json $w/b.json "$@" > /dev/null 2> $w/err.txt \
    || { echo "$label failed: $(tail -2 $w/err.txt)"; return; }
  python3 - "$label" $w/b.json <<'PY'
import json, sys
j = json.load(open(sys.argv[2]))
print(sys.argv[1].ljust(14), ' '.join('%s %.3f' % (x['name'], x['grays_per_s']) for x in j['scenarios']), flush=True)
PY
}
s="$w/surf.pool --surface iso --scenarios reflect4,full4"
for r in 1 2; do
  bench base $x/prt-bench-base $s
  bench exp-general $x/prt-bench $s
  for b in 3 4 5; do PRT_EXP_ISO2=1 bench exp-iso2-$b $x/prt-bench $s --min-blocks $b; done
done
echo "bench done $((SECONDS - t0)) s"
ncu=/usr/local/cuda/bin/ncu; [ -x $ncu ] || ncu=$(ls /usr/local/cuda*/bin/ncu 2>/dev/null | head -1)
for v in general iso2-4; do
  env=""; mb=""; [ $v = iso2-4 ] && env="PRT_EXP_ISO2=1" && mb="--min-blocks 4"
  env $env timeout 150 $ncu --kernel-name regex:render_kernel --launch-skip 3 --launch-count 1 --section SpeedOfLight \
    --section Occupancy --section WarpStateStats --section LaunchStats --section SchedulerStats \
    $x/prt-bench --backend cuda --frames 2 --warmup 2 $w/surf.pool --surface iso --scenarios full4 $mb $q > $out/ncu-$v.txt 2>&1
  echo "ncu $v rc $? $((SECONDS - t0)) s"
done
echo ALL_DONE
