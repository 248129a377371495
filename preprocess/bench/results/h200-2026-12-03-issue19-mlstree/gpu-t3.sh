#!/usr/bin/env bash
# Issue 19, MLS on the GPU (H200), third call: the change as committed (pack9): prt-mls's new
# defaults (no E(n), 128 slices, C_trav 3) and the samples per support radius (core/mls.h), the GPU
# tests, then the culled room and the 1M sphere against the old tree (--encourage --slices 8
# --cost-traversal 1) traced as before (--mls-support-samples 0), 2 rounds.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/t3.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; t0=$SECONDS
rm -rf /tmp/ab; mkdir -p /tmp/ab
python3 -c "import tarfile; tarfile.open('build-ab/pack9.tar.xz').extractall('/tmp/ab')"
x=/tmp/ab/p9; w=/tmp/t3; rm -rf $w; mkdir -p $w; q=--quiet
mkdir -p /work/main/build-cu && ln -sfn "$x" /work/main/build-cu/bin
for t in prt_stability_gpu_tests prt_mls_gpu_tests prt_runtime_gpu_tests prt_iso_gpu_tests; do
  PRT_BIN_DIR=$x $x/$t > $out/$t.log 2>&1; echo "$t rc $? $(grep -E '^\[  (PASSED|FAILED|SKIPPED)' $out/$t.log | tr '\n' ' ')"
done
grep -A3 "Failure" $out/*.log | head -20
$x/prt-bench --save-pool $w/room.pool --frames 1 --warmup 0 --scenarios primary --backend cuda $q > /dev/null
$x/prt-cull $w/room.pool -o $w/culled.pool $q
$x/prt-synth sphere -n 1000000 -o $w/sphere.pool $q && $x/prt-radii $w/sphere.pool -o $w/sphere.pool $q
OLD="--encourage --slices 8 --cost-traversal 1"
for m in room:culled sphere:sphere; do n=${m%%:*}; p=${m#*:}
  s=$SECONDS; $x/prt-mls $w/$p.pool -o $w/$n-old.pool $q $OLD; r=$((SECONDS - s))
  s=$SECONDS; $x/prt-mls $w/$p.pool -o $w/$n-new.pool $q; echo "built $n: old ${r} s, new $((SECONDS - s)) s"
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
  bench "room old s0" $w/room-old.pool --scenarios $S --mls-support-samples 0
  bench "room old s3" $w/room-old.pool --scenarios $S
  for s in 0 2 3; do bench "room new s$s" $w/room-new.pool --scenarios $S --mls-support-samples $s; done
  bench "sphere old s0" $w/sphere-old.pool --scenarios $S $SPH --mls-support-samples 0
  for s in 0 3; do bench "sphere new s$s" $w/sphere-new.pool --scenarios $S $SPH --mls-support-samples $s; done
done
$x/prt-bench --backend cuda --frames 1 --warmup 0 --surface mls $w/room-new.pool --scenarios primary --save-image $out/room-new.ppm > /dev/null 2>&1 || true
echo "ALL_DONE $((SECONDS - t0)) s"
