#!/usr/bin/env bash
# Issue 19 on the GPU host (one H200), 2026-12-02: frames with secondary rays when each warp's
# lanes stay in the ray-tree loop until all are done (__any_sync at its head: s1) and also
# reconverge after each closest hit (__syncwarp: s2), against the loop as it is (exp: the same
# binary as the landed code but for the ISO kernel with secondary rays behind PRT_EXP_ISO2; base:
# the landed prt-bench). prt-bench's room (splats), the culled room's ISO; 1024x1024, median of 30
# frames after 5, two alternating rounds.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/e2.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; t0=$SECONDS
x=$PWD/build-ab/exp; c=$PWD/build-ab/cur; w=/tmp/e2; mkdir -p $w; q=--quiet
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
print(sys.argv[1].ljust(22), ' '.join('%s %.3f' % (x['name'], x['grays_per_s']) for x in j['scenarios']), flush=True)
PY
}
iso="$w/surf.pool --surface iso --scenarios reflect4,full4"
spl="--scenarios primary,reflect4,full4"
cul="$w/culled.pool --scenarios reflect4,full4"
for r in 1 2; do
  for v in base exp s1 s2; do
    bin=$x/prt-bench; [ $v = base ] && bin=$x/prt-bench-base; [ $v = s1 ] && bin=$x/prt-bench-s1; [ $v = s2 ] && bin=$x/prt-bench-s2
    bench "room $v" $bin $spl
    bench "culled $v" $bin $cul
    bench "iso-general $v" $bin $iso
    [ $v != base ] && PRT_EXP_ISO2=1 bench "iso2-4 $v" $bin $iso --min-blocks 4
    [ $v != base ] && PRT_EXP_ISO2=1 bench "iso2-3 $v" $bin $iso --min-blocks 3
  done
  echo "round $r done $((SECONDS - t0)) s"
done
echo ALL_DONE
