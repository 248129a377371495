#!/usr/bin/env bash
# Node boxes with the test mask (this tree, "mask") against every internal child tested (gpu-x4's
# binary, "all") and none ("off": the prototype binary with them off), prt-bench on the H200,
# 1024x1024, median of 30 frames after 5, alternating, two rounds; then prt_runtime_gpu_tests.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/x7.txt") 2>&1
nvidia-smi --query-gpu=name --format=csv,noheader; t0=$SECONDS
root=$PWD; rm -rf /tmp/ab; mkdir -p /tmp/ab; python3 -c "import tarfile; tarfile.open('build-ab/pack.tar.xz').extractall('/tmp/ab')"
new=/tmp/ab/new; w=/tmp/x7; rm -rf $w; mkdir -p $w; q=--quiet
mkdir -p /work/main/build-cu && ln -sfn "$new" /work/main/build-cu/bin
$new/prt-bench --save-pool $w/room.pool --frames 1 --warmup 0 --width 16 --height 16 --scenarios primary $q > /dev/null
$new/prt-cull $w/room.pool -o $w/culled.pool $q
sed 's/"room.pool"/"culled.pool"/' $root/preprocess/bench/bench_room.json > $w/scene_c.json
$new/prt-iso $w/culled.pool -o $w/surf.pool $q
for n in 1000000 10000000; do
  $new/prt-synth sphere -n $n -o $w/s$n.pool $q && $new/prt-radii $w/s$n.pool -o $w/s$n.pool --backend cuda $q \
    && $new/prt-octree $w/s$n.pool -o $w/s$n.pool $q && $new/prt-cull $w/s$n.pool -o $w/s$n.pool $q || echo "sphere $n failed"
done
echo "pools done $((SECONDS - t0)) s"
bench() {  # bench LABEL VARIANT ARGS...
  local label=$1 v=$2; shift 2; local bin=$root/build-ab/x7/prt-bench
  [ "$v" = off ] && bin=/tmp/ab/nb/prt-bench
  [ "$v" = all ] && bin=$new/prt-bench
  $bin --backend cuda --frames 30 --warmup 5 --json $w/b.json "$@" > /dev/null 2> $w/err.txt \
    || { echo "$label $v failed: $(tail -2 $w/err.txt)"; return; }
  python3 - "$label" "$v" $w/b.json <<'PY'
import json, sys
j = json.load(open(sys.argv[3]))
print(sys.argv[1].ljust(10), sys.argv[2].ljust(5), ' '.join('%s %.3f (%.1f)' % (x['name'], x['grays_per_s'], x['leaves_per_ray']) for x in j['scenarios']), flush=True)
PY
}
cam="--eye 0,0,3 --look-at 0,0,0 --up 0,1,0 --fov 45"
for r in 1 2; do
  for v in off all mask; do
    bench culled $v $w/culled.pool --scene $w/scene_c.json --scenarios primary,shadow,reflect4,full4
    bench default $v --scenarios primary,shadow,reflect4,full4
    bench sphere1m $v $w/s1000000.pool $cam --scenarios primary,shadow,reflect4
    bench sphere10m $v $w/s10000000.pool $cam --scenarios primary,shadow,reflect4,full4
    bench iso $v $w/surf.pool --surface iso --scenarios primary,full4
  done
  echo "round $r done $((SECONDS - t0)) s"
done
timeout 200 $root/build-ab/x7/prt_runtime_gpu_tests > $w/rt.log 2>&1; echo "prt_runtime_gpu_tests rc $?"
grep -E "^\[  (PASSED|FAILED|SKIPPED) |Failure" $w/rt.log | head -20
echo "ALL_DONE $((SECONDS - t0)) s"
