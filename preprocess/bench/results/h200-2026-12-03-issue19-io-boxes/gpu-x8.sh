#!/usr/bin/env bash
# The committed node boxes (descend_path<Boxed>, the mask): GPU test programs that render splats,
# and prt-bench against the boxes off, one round.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/x8.txt") 2>&1
nvidia-smi --query-gpu=name --format=csv,noheader; t0=$SECONDS
root=$PWD; rm -rf /tmp/ab; mkdir -p /tmp/ab; python3 -c "import tarfile; tarfile.open('build-ab/pack.tar.xz').extractall('/tmp/ab')"
cp build-ab/x5/prt-import build-ab/x5/prt-info build-ab/x8/prt-bench build-ab/x8/prt-play /tmp/ab/new/
new=/tmp/ab/new; w=/tmp/x8; rm -rf $w; mkdir -p $w; q=--quiet
mkdir -p /work/main/build-cu && ln -sfn "$new" /work/main/build-cu/bin
for t in prt_runtime_gpu_tests prt_stability_gpu_tests; do
  timeout 200 build-ab/x8/$t > $w/$t.log 2>&1; echo "$t: rc $? $(grep -E '^\[  (PASSED|FAILED|SKIPPED) ' $w/$t.log | tr '\n' ' ')"
done
$new/prt-bench --save-pool $w/room.pool --frames 1 --warmup 0 --width 16 --height 16 --scenarios primary $q > /dev/null
$new/prt-cull $w/room.pool -o $w/culled.pool $q
sed 's/"room.pool"/"culled.pool"/' $root/preprocess/bench/bench_room.json > $w/scene_c.json
n=10000000; $new/prt-synth sphere -n $n -o $w/s$n.pool $q && $new/prt-radii $w/s$n.pool -o $w/s$n.pool --backend cuda $q \
    && $new/prt-octree $w/s$n.pool -o $w/s$n.pool $q && $new/prt-cull $w/s$n.pool -o $w/s$n.pool $q || echo "sphere $n failed"
bench() {  # bench LABEL VARIANT ARGS...
  local label=$1 v=$2; shift 2; local bin=$new/prt-bench
  [ "$v" = off ] && bin=/tmp/ab/nb/prt-bench
  $bin --backend cuda --frames 30 --warmup 5 --json $w/b.json "$@" > /dev/null 2> $w/err.txt \
    || { echo "$label $v failed: $(tail -2 $w/err.txt)"; return; }
  python3 - "$label" "$v" $w/b.json <<'PY'
import json, sys
j = json.load(open(sys.argv[3]))
print(sys.argv[1].ljust(10), sys.argv[2].ljust(5), ' '.join('%s %.3f (%.1f)' % (x['name'], x['grays_per_s'], x['leaves_per_ray']) for x in j['scenarios']), flush=True)
PY
}
cam="--eye 0,0,3 --look-at 0,0,0 --up 0,1,0 --fov 45"
for v in off final; do
  bench culled $v $w/culled.pool --scene $w/scene_c.json --scenarios primary,shadow,reflect4,full4
  bench sphere10m $v $w/s10000000.pool $cam --scenarios primary,shadow,reflect4,full4
done
for v in off final; do
  b=$new/prt-play; [ "$v" = off ] && b=$new/prt-play-none
  [ "$v" = off ] && continue
  $new/prt-play $w/culled.pool --scene $w/scene_c.json --backend cuda --out $w/img-cuda.ppm $q
  $new/prt-play $w/culled.pool --scene $w/scene_c.json --backend cpu --out $w/img-cpu.ppm $q
done
python3 - $w/img-cuda.ppm $w/img-cpu.ppm <<'PY'
import sys
a = open(sys.argv[1], 'rb').read(); b = open(sys.argv[2], 'rb').read()
print('CUDA and CPU images of the culled room:', len(a), 'bytes;', sum(x != y for x, y in zip(a, b)), 'bytes differ')
PY
echo "ALL_DONE $((SECONDS - t0)) s"
