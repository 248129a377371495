#!/usr/bin/env bash
# Issue 19 on the GPU host (one H200), 2026-12-02, second call: the kernels as committed (ISO's own
# kernel for frames without secondary rays only; MLS on the general kernel), against the landed tree
# (fae5e6d): the GPU test programs first, then prt-bench on prt-bench's own synthetic room (no pool:
# the issue's scene and camera), the culled room's ISO and MLS, and the culled 10M-point sphere
# (camera z = 3, fov 45), alternating base and new, two rounds, 1024x1024, median of 30 frames after 5.
# Binaries built on the dev VM as for gpu-k2.sh and carried in build-ab/{base,new}.
# Usage (repository root): bash preprocess/bench/results/h200-2026-12-02-issue19-kernels/gpu-k3.sh
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/k3.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; t0=$SECONDS
new=$PWD/build-ab/new/bin; base=$PWD/build-ab/base/bin; w=/tmp/k3; rm -rf $w; mkdir -p $w
mkdir -p /work/main/build-cu && ln -sfn "$new" /work/main/build-cu/bin
for t in build-ab/new/tests/*; do
  timeout 200 $t > $out/$(basename $t)-k3.log 2>&1; echo "$(basename $t): rc $? $(grep -E '^\[  (PASSED|FAILED|SKIPPED) ' $out/$(basename $t)-k3.log | tr '\n' ' ')"
done
echo "tests done $((SECONDS - t0)) s"
q=--quiet
$new/prt-bench --save-pool $w/room.pool --frames 1 --warmup 0 --scenarios primary $q > /dev/null
$new/prt-cull $w/room.pool -o $w/culled.pool $q
$new/prt-iso $w/culled.pool -o $w/surf.pool $q && $new/prt-mls $w/surf.pool -o $w/surf.pool $q
$new/prt-synth sphere -n 10000000 -o $w/s10.pool $q && $new/prt-radii $w/s10.pool -o $w/s10.pool --backend cuda $q \
  && $new/prt-octree $w/s10.pool -o $w/s10.pool $q && $new/prt-cull $w/s10.pool -o $w/s10.pool $q || echo "sphere failed"
ls -la $w; echo "pools done $((SECONDS - t0)) s"
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
cam="--eye 0,0,3 --look-at 0,0,0 --up 0,1,0 --fov 45"
for r in 1 2; do
  for v in base new; do
    bench default $v --scenarios primary,shadow,reflect4,full4
    bench iso $v $w/surf.pool --surface iso --scenarios primary,shadow,full4
    bench mls $v $w/surf.pool --surface mls --scenarios primary
    bench sphere10m $v $w/s10.pool $cam --scenarios primary,shadow,reflect4,full4
  done
  echo "round $r done $((SECONDS - t0)) s"
done
echo "ALL_DONE $((SECONDS - t0)) s"
