#!/usr/bin/env bash
# Issue 19 on the GPU host (one H200), 2026-12-02: megakernels per surface kind and without
# secondary rays, against the landed tree (fae5e6d). The binaries were built on the dev VM with
# CUDA 13 (sm_90, CUDA's static runtime; no PCL, OpenMesh, OIIO, GLFW, Embree) and carried in
# build-ab/{base,new}: base's prt-bench, this tree's prt-bench, tools and three GPU test programs.
# The pools come from this tree's tools (the pool format did not change). prt-bench runs on both
# alternating, two rounds, 1024x1024, median of 30 frames after 5; then the GPU test programs.
# (A first version built both trees here and waited on its own output's tee: it ran out of time.)
# Usage (repository root): bash preprocess/bench/results/h200-2026-12-02-issue19-kernels/gpu-k2.sh
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/k2.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; t0=$SECONDS
new=$PWD/build-ab/new/bin; base=$PWD/build-ab/base/bin; w=/tmp/k2; rm -rf $w; mkdir -p $w
# The test programs look for the tools where the dev VM built them.
mkdir -p /work/main/build-cu && ln -sfn "$new" /work/main/build-cu/bin
q=--quiet
$new/prt-bench --save-pool $w/room.pool --frames 1 --warmup 0 --scenarios primary $q > /dev/null
$new/prt-cull $w/room.pool -o $w/culled.pool $q
$new/prt-iso $w/culled.pool -o $w/surf.pool $q && $new/prt-mls $w/surf.pool -o $w/surf.pool $q
$new/prt-bricks $w/culled.pool -o $w/bricked.pool --keep-float $q
$new/prt-patches .device-deps/teapot.bpt -o $w/teapot.pool $q
ls -la $w; echo "pools done $((SECONDS - t0)) s"
bench() {  # bench LABEL VARIANT ARGS...
  local label=$1 v=$2; shift 2; local bin=$new; [ "$v" = base ] && bin=$base
  $bin/prt-bench --backend cuda --frames 30 --warmup 5 --json $w/b.json "$@" > /dev/null 2> $w/err.txt \
    || { echo "$label $v failed: $(tail -2 $w/err.txt)"; return; }
  python3 - "$label" "$v" $w/b.json <<'PY'
import json, sys
j = json.load(open(sys.argv[3]))
print(sys.argv[1].ljust(8), sys.argv[2].ljust(5), ' '.join('%s %.3f' % (x['name'], x['grays_per_s']) for x in j['scenarios']), flush=True)
PY
}
for r in 1 2; do
  for v in base new; do
    bench room $v $w/room.pool --scenarios primary,shadow,reflect4,full4
    bench culled $v $w/culled.pool --scenarios primary,shadow,reflect4,full4
    bench bricks $v $w/bricked.pool --bricks --scenarios primary,shadow,full4
    bench iso $v $w/surf.pool --surface iso --scenarios primary,shadow,full4
    bench mls $v $w/surf.pool --surface mls --scenarios primary,shadow
    bench teapot $v $w/teapot.pool --max-bounces 1 --scenarios primary,shadow,reflect4
  done
  echo "round $r done $((SECONDS - t0)) s"
done
for t in build-ab/new/tests/*; do
  timeout 200 $t > $out/$(basename $t).log 2>&1; echo "$(basename $t): rc $? $(grep -E '^\[  (PASSED|FAILED|SKIPPED) ' $out/$(basename $t).log | tr '\n' ' ')"
done
echo "ALL_DONE $((SECONDS - t0)) s"
