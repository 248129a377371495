#!/usr/bin/env bash
# Issue 19 (H200): heavy items first (the previous frame's slow 32-pixel items handed out first by
# the persistent megakernel's queue) against the image-order queue (--kernel mega-fifo): the GPU
# runtime tests, then prt-bench on the teapot, Bigguy and prt-bench's room, alternating, two rounds.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/q3.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; t0=$SECONDS
rm -rf /tmp/ab; mkdir -p /tmp/ab
for p in pack10 pack22; do python3 -c "import tarfile; tarfile.open('build-ab/$p.tar.xz').extractall('/tmp/ab')"; done
x=/tmp/ab/p10; n=/tmp/ab/p22; w=/tmp/q3; mkdir -p $w; q=--quiet
mkdir -p /work/shared/data/bezier && cp build-ab/bezier/* /work/shared/data/bezier/
mkdir -p /work/main/build-cu && ln -sfn "$x" /work/main/build-cu/bin
PRT_BIN_DIR=$x timeout 300 $n/prt_runtime_gpu_tests > $out/prt_runtime_gpu_tests.log 2>&1; echo "prt_runtime_gpu_tests rc $? $(grep -E '^\[  (PASSED|FAILED|SKIPPED)' $out/prt_runtime_gpu_tests.log | tr '\n' ' ')"
grep -B2 -A6 "Failure" $out/prt_runtime_gpu_tests.log | head -30
$x/prt-patches build-ab/bezier/teapot.bpt -o $w/teapot.pool $q
$x/prt-patches build-ab/bezier/bigguy -o $w/bigguy.pool $q
$n/prt-bench --backend cuda --synthetic 1000000 --save-pool $w/room.pool --frames 1 --warmup 0 --scenarios primary $q > /dev/null 2>&1
$x/prt-iso $w/room.pool -o $w/roomiso.pool $q
$x/prt-synth sphere -n 1000000 -o $w/sphere.pool $q && $x/prt-radii $w/sphere.pool -o $w/sphere.pool $q && $x/prt-octree $w/sphere.pool -o $w/sphere.pool $q && $x/prt-cull $w/sphere.pool -o $w/sphere.pool $q
echo "pools made $((SECONDS - t0)) s"
sph="--eye 0,0,3 --look-at 0,0,0 --up 0,1,0 --fov 45"
bench() {  # bench LABEL ARGS...
  local label=$1; shift
  $n/prt-bench --backend cuda --frames 30 --warmup 5 --json $w/b.json "$@" > /dev/null 2> $w/err.txt \
    || { echo "$label failed: $(tail -2 $w/err.txt)"; return; }
  python3 - "$label" $w/b.json <<'PY'
import json, sys
j = json.load(open(sys.argv[2]))
print(sys.argv[1].ljust(24), ' '.join('%s %.3f (%d)' % (x['name'], x['grays_per_s'], x.get('heavy_first_items', -1)) for x in j['scenarios']), flush=True)
PY
}
for r in 1 2; do for k in mega-fifo mega; do
  bench "teapot $k" $w/teapot.pool --kernel $k --max-bounces 1 --scenarios primary,shadow,reflect4
  bench "bigguy $k" $w/bigguy.pool --kernel $k --max-bounces 1 --scenarios primary,shadow,reflect4
  bench "room $k" $w/room.pool --scene preprocess/bench/bench_room.json --kernel $k --scenarios primary,shadow,reflect4,full4
  bench "room iso $k" $w/roomiso.pool --scene preprocess/bench/bench_room.json --surface iso --kernel $k --scenarios primary,shadow,full4
  bench "sphere $k" $w/sphere.pool $sph --kernel $k --scenarios primary,shadow,reflect4
done; done
for f in 1.5 3; do
  PRT_HEAVY_FACTOR=$f bench "teapot mega f$f" $w/teapot.pool --max-bounces 1 --scenarios primary,shadow,reflect4
  PRT_HEAVY_FACTOR=$f bench "bigguy mega f$f" $w/bigguy.pool --max-bounces 1 --scenarios primary,shadow,reflect4
  PRT_HEAVY_FACTOR=$f bench "room mega f$f" $w/room.pool --scene preprocess/bench/bench_room.json --scenarios primary,shadow,reflect4,full4
done
for k in mega-fifo mega; do bench "teapot 2048 $k" $w/teapot.pool --kernel $k --max-bounces 1 --scenarios primary,reflect4 --width 2048 --height 2048; done
echo "ALL_DONE $((SECONDS - t0)) s"
