#!/usr/bin/env bash
# Issue 19 on the GPU host (one H200), 2026-12-02, fourth call: the committed tree (ISO's kernel
# without secondary rays at 3 blocks per SM by default): its GPU test programs, then prt-bench on
# ISO over the culled room and on prt-bench's room, base against new, two rounds.
# Usage (repository root): bash preprocess/bench/results/h200-2026-12-02-issue19-kernels/gpu-k5.sh
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/k5.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; t0=$SECONDS
new=$PWD/build-ab/new/bin; base=$PWD/build-ab/base/bin; w=/tmp/k5; rm -rf $w; mkdir -p $w
mkdir -p /work/main/build-cu && ln -sfn "$new" /work/main/build-cu/bin
for t in build-ab/new/tests/*; do
  timeout 200 $t > $out/$(basename $t)-k5.log 2>&1; echo "$(basename $t): rc $? $(grep -E '^\[  (PASSED|FAILED|SKIPPED) ' $out/$(basename $t)-k5.log | tr '\n' ' ')"
done
echo "tests done $((SECONDS - t0)) s"
q=--quiet
$new/prt-bench --save-pool $w/room.pool --frames 1 --warmup 0 --scenarios primary $q > /dev/null
$new/prt-cull $w/room.pool -o $w/culled.pool $q && $new/prt-iso $w/culled.pool -o $w/surf.pool $q
bench() {  # bench LABEL VARIANT ARGS...
  local label=$1 v=$2; shift 2; local bin=$new; [ "$v" = base ] && bin=$base
  $bin/prt-bench --backend cuda --frames 30 --warmup 5 --json $w/b.json "$@" > /dev/null 2> $w/err.txt \
    || { echo "$label $v failed: $(tail -2 $w/err.txt)"; return; }
  python3 - "$label" "$v" $w/b.json <<'PY'
import json, sys
j = json.load(open(sys.argv[3]))
print(sys.argv[1].ljust(9), sys.argv[2].ljust(5), ' '.join('%s %.3f' % (x['name'], x['grays_per_s']) for x in j['scenarios']), flush=True)
PY
}
for r in 1 2; do
  for v in base new; do
    bench default $v --scenarios primary,shadow,full4
    bench iso $v $w/surf.pool --surface iso --scenarios primary,shadow,full4
  done
done
echo "ALL_DONE $((SECONDS - t0)) s"
