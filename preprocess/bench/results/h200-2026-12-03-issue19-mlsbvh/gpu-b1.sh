#!/usr/bin/env bash
# Issue 19, MLS on the GPU (H200): a BVH over the kd-tree's non-empty leaves (prt-mls pass 5,
# core/mls.h mls_walk_bvh) against the kd walk (prt-mls --no-bvh), same binaries (pack10): the GPU
# tests, then the culled 1M room and the 1M sphere, two alternating rounds.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/b1.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; t0=$SECONDS
rm -rf /tmp/ab; mkdir -p /tmp/ab
python3 -c "import tarfile; tarfile.open('build-ab/pack10.tar.xz').extractall('/tmp/ab')"
x=/tmp/ab/p10; w=/tmp/b1; rm -rf $w; mkdir -p $w; q=--quiet
mkdir -p /work/main/build-cu && ln -sfn "$x" /work/main/build-cu/bin
for t in prt_mls_gpu_tests prt_stability_gpu_tests prt_runtime_gpu_tests prt_iso_gpu_tests; do
  PRT_BIN_DIR=$x timeout 200 $x/$t > $out/$t.log 2>&1; echo "$t rc $? $(grep -E '^\[  (PASSED|FAILED|SKIPPED)' $out/$t.log | tr '\n' ' ')"
done
grep -h "measured" $out/prt_mls_gpu_tests.log
grep -A3 "Failure" $out/*.log | head -20
echo "tests done $((SECONDS - t0)) s"
$x/prt-bench --save-pool $w/room.pool --frames 1 --warmup 0 --scenarios primary --backend cuda $q > /dev/null
$x/prt-cull $w/room.pool -o $w/culled.pool $q
$x/prt-synth sphere -n 1000000 -o $w/sphere.pool $q && $x/prt-radii $w/sphere.pool -o $w/sphere.pool $q
for m in room:culled sphere:sphere; do n=${m%%:*}; p=${m#*:}
  s=$SECONDS; $x/prt-mls $w/$p.pool -o $w/$n-bvh.pool 2>&1 | grep -E "BVH|wrote"
  $x/prt-mls $w/$p.pool -o $w/$n-kd.pool $q --no-bvh; echo "built $n: $((SECONDS - s)) s"
done
bench() {  # bench LABEL POOL ARGS...
  local label=$1 pool=$2; shift 2
  $x/prt-bench --backend cuda --frames 20 --warmup 3 --surface mls --json $w/b.json $pool "$@" > /dev/null 2> $w/err.txt \
    || { echo "$label failed: $(tail -2 $w/err.txt)"; return; }
  python3 - "$label" $w/b.json <<'PY'
import json, sys
j = json.load(open(sys.argv[2]))
print(sys.argv[1].ljust(24), ' '.join('%s %.4f' % (x['name'], x['grays_per_s']) for x in j['scenarios']), flush=True)
PY
}
S=primary,shadow,reflect4,full4; SPH="--eye 0,0,3 --look-at 0,0,0 --up 0,1,0 --fov 45"
for round in 1 2; do
  bench "room kd" $w/room-kd.pool --scenarios $S
  bench "room bvh" $w/room-bvh.pool --scenarios $S
  bench "sphere kd" $w/sphere-kd.pool --scenarios $S $SPH
  bench "sphere bvh" $w/sphere-bvh.pool --scenarios $S $SPH
done
bench "room bvh s0" $w/room-bvh.pool --scenarios $S --mls-support-samples 0
bench "sphere bvh s0" $w/sphere-bvh.pool --scenarios $S $SPH --mls-support-samples 0
for v in kd bvh; do $x/prt-play $w/room-$v.pool --surface mls --backend cuda --out $out/room-$v.ppm --quiet 2>&1 | tail -2; done
cmp $out/room-kd.ppm $out/room-bvh.ppm && echo "room images kd/bvh identical"
echo "ALL_DONE $((SECONDS - t0)) s"
