#!/usr/bin/env bash
# Issue 19 (H200): heavy items first under a moving camera: prt-bench --orbit (the camera turns 1 or
# 5 degrees about its look-at point every frame, warm-up frames included), median of 60 frames after
# 5, --kernel mega against mega-fifo, two rounds: the teapot, Bigguy, the culled room.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/q6.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; t0=$SECONDS
rm -rf /tmp/ab; mkdir -p /tmp/ab
for p in pack10 pack24; do python3 -c "import tarfile; tarfile.open('build-ab/$p.tar.xz').extractall('/tmp/ab')"; done
n=/tmp/ab/p24; x=/tmp/ab/p10; w=/tmp/q6; mkdir -p $w; q=--quiet
$x/prt-patches build-ab/bezier/teapot.bpt -o $w/teapot.pool $q
$x/prt-patches build-ab/bezier/bigguy -o $w/bigguy.pool $q
$n/prt-bench --backend cuda --save-pool $w/room.pool --frames 1 --warmup 0 --scenarios primary $q > /dev/null 2>&1
$x/prt-cull $w/room.pool -o $w/culled.pool $q
bench() {  # bench LABEL ARGS...
  local label=$1; shift
  $n/prt-bench --backend cuda --frames 60 --warmup 5 --json $w/b.json "$@" > /dev/null 2> $w/err.txt \
    || { echo "$label failed: $(tail -2 $w/err.txt)"; return; }
  python3 - "$label" $w/b.json <<'PY'
import json, sys
j = json.load(open(sys.argv[2]))
print(sys.argv[1].ljust(28), ' '.join('%s %.3f (%d)' % (x['name'], x['grays_per_s'], x.get('heavy_first_items', -1)) for x in j['scenarios']), flush=True)
PY
}
for r in 1 2; do for d in 0 1 5; do for k in mega-fifo mega; do
  bench "teapot orbit $d $k" $w/teapot.pool --orbit $d --kernel $k --max-bounces 1 --scenarios primary,shadow,reflect4
  bench "bigguy orbit $d $k" $w/bigguy.pool --orbit $d --kernel $k --max-bounces 1 --scenarios primary,shadow,reflect4
  bench "culled room orbit $d $k" $w/culled.pool --scene preprocess/bench/bench_room.json --orbit $d --kernel $k --scenarios primary,shadow,full4
done; done; done
echo "ALL_DONE $((SECONDS - t0)) s"
