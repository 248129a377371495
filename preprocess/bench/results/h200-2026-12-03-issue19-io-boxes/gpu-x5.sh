#!/usr/bin/env bash
# Node boxes, three layouts in one binary (PRT_BOX_MODE: 0 off, 1 boxes by children block tested at
# every level, 2 boxes by node slot read beside the node word at every level, 3 as 2 at the first
# new level of each descent only); then the stability GPU tests with prt-import present.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/x5.txt") 2>&1
nvidia-smi --query-gpu=name --format=csv,noheader; t0=$SECONDS
root=$PWD; rm -rf /tmp/ab; mkdir -p /tmp/ab; python3 -c "import tarfile; tarfile.open('build-ab/pack.tar.xz').extractall('/tmp/ab')"
cp build-ab/x5/prt-import /tmp/ab/new/
new=/tmp/ab/new; x=$root/build-ab/x5; w=/tmp/x5; rm -rf $w; mkdir -p $w
mkdir -p /work/main/build-cu && ln -sfn "$new" /work/main/build-cu/bin
q=--quiet
$new/prt-bench --save-pool $w/room.pool --frames 1 --warmup 0 --width 16 --height 16 --scenarios primary $q > /dev/null
$new/prt-cull $w/room.pool -o $w/culled.pool $q
sed 's/"room.pool"/"culled.pool"/' $root/preprocess/bench/bench_room.json > $w/scene_c.json
for n in 1000000 10000000; do
  $new/prt-synth sphere -n $n -o $w/s$n.pool $q && $new/prt-radii $w/s$n.pool -o $w/s$n.pool --backend cuda $q \
    && $new/prt-octree $w/s$n.pool -o $w/s$n.pool $q && $new/prt-cull $w/s$n.pool -o $w/s$n.pool $q || echo "sphere $n failed"
done
echo "pools done $((SECONDS - t0)) s"
bench() {  # bench LABEL MODE ARGS...
  local label=$1 v=$2; shift 2
  PRT_BOX_MODE=$v $x/prt-bench --backend cuda --frames 30 --warmup 5 --json $w/b.json "$@" > /dev/null 2> $w/err.txt \
    || { echo "$label $v failed: $(tail -2 $w/err.txt)"; return; }
  python3 - "$label" "$v" $w/b.json <<'PY'
import json, sys
j = json.load(open(sys.argv[3]))
print(sys.argv[1].ljust(10), ('mode ' + sys.argv[2]).ljust(7), ' '.join('%s %.3f (%.1f)' % (x['name'], x['grays_per_s'], x['leaves_per_ray']) for x in j['scenarios']), flush=True)
PY
}
cam="--eye 0,0,3 --look-at 0,0,0 --up 0,1,0 --fov 45"
for r in 1 2; do
  for v in 0 1 2 3; do
    bench culled $v $w/culled.pool --scene $w/scene_c.json --scenarios primary,shadow,reflect4,full4
    bench default $v --scenarios primary,shadow,reflect4,full4
    bench sphere1m $v $w/s1000000.pool $cam --scenarios primary,shadow,reflect4
    bench sphere10m $v $w/s10000000.pool $cam --scenarios primary,shadow,reflect4,full4
  done
  echo "round $r done $((SECONDS - t0)) s"
done
timeout 200 /tmp/ab/tests/prt_stability_gpu_tests > $w/stab.log 2>&1; echo "stability rc $?"
grep -E "^\[  (PASSED|FAILED|SKIPPED) |Failure|error|differ" $w/stab.log | head -30
echo "ALL_DONE $((SECONDS - t0)) s"
