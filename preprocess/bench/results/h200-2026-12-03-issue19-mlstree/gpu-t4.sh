#!/usr/bin/env bash
# Issue 19, MLS on the GPU (H200), fourth call: pack9 again, the samples per support radius at 0, 1.5, 2, 3 on the new trees (one round;
# t3 ran the GPU tests):
# old header of t3: the change as committed (pack9): prt-mls's new
# defaults (no E(n), 128 slices, C_trav 3) and the samples per support radius (core/mls.h), the GPU
# tests, then the culled room and the 1M sphere against the old tree (--encourage --slices 8
# --cost-traversal 1) traced as before (--mls-support-samples 0), 2 rounds.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/t4.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; t0=$SECONDS
rm -rf /tmp/ab; mkdir -p /tmp/ab
python3 -c "import tarfile; tarfile.open('build-ab/pack9.tar.xz').extractall('/tmp/ab')"
x=/tmp/ab/p9; w=/tmp/t4; rm -rf $w; mkdir -p $w; q=--quiet
mkdir -p /work/main/build-cu && ln -sfn "$x" /work/main/build-cu/bin
$x/prt-bench --save-pool $w/room.pool --frames 1 --warmup 0 --scenarios primary --backend cuda $q > /dev/null
$x/prt-cull $w/room.pool -o $w/culled.pool $q
$x/prt-synth sphere -n 1000000 -o $w/sphere.pool $q && $x/prt-radii $w/sphere.pool -o $w/sphere.pool $q
OLD="--encourage --slices 8 --cost-traversal 1"
for m in room:culled sphere:sphere; do n=${m%%:*}; p=${m#*:}
  $x/prt-mls $w/$p.pool -o $w/$n-new.pool $q
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
for s in 0 1.5 2 3; do
  bench "room new s$s" $w/room-new.pool --scenarios $S --mls-support-samples $s
  bench "sphere new s$s" $w/sphere-new.pool --scenarios $S $SPH --mls-support-samples $s
done
echo "ALL_DONE $((SECONDS - t0)) s"
