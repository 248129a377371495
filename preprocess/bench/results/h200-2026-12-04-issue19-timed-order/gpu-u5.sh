#!/usr/bin/env bash
# Issue 19 (H200): u4 found heavy items first path dependent: the lists a scenario inherits from the
# one before (prt-bench runs them in one process, on one backend) can settle at more items and a
# faster frame (the culled room's full4 after reflect4: 563 items, 7.98 ms; alone: 497-506, 8.5 ms).
# So every scenario here runs alone, in its own process: image order (mega-fifo), heavy items first
# (mega-heavy) and the timed order (mega), two rounds.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/u5.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; t0=$SECONDS
rm -rf /tmp/ab; mkdir -p /tmp/ab
python3 -c "import tarfile; tarfile.open('build-ab/pack.tar.xz').extractall('/tmp/ab')"
x=/tmp/ab/bin; w=/tmp/u5; mkdir -p $w; q=--quiet
$x/prt-patches build-ab/bezier/teapot.bpt -o $w/teapot.pool $q
$x/prt-bench --backend cuda --save-pool $w/room.pool --frames 1 --warmup 0 --scenarios primary $q > /dev/null 2>&1
$x/prt-cull $w/room.pool -o $w/culled.pool $q
$x/prt-synth sphere -n 10000000 -o $w/s10.pool $q && $x/prt-radii $w/s10.pool -o $w/s10.pool --backend cuda $q \
  && $x/prt-octree $w/s10.pool -o $w/s10.pool $q && $x/prt-cull $w/s10.pool -o $w/s10.pool $q || echo "sphere failed"
echo "pools done $((SECONDS - t0)) s"
alone() {  # alone LABEL SCENARIOS ARGS...: each scenario in its own process
  local label=$1 scs=$2; shift 2; local line="$label"
  for sc in ${scs//,/ }; do
    $x/prt-bench --backend cuda --frames 30 --warmup 5 --json $w/b.json "$@" --scenarios $sc > /dev/null 2> $w/err.txt \
      || { line="$line $sc failed"; continue; }
    line="$line $(python3 -c "import json; s=json.load(open('$w/b.json'))['scenarios'][0]; print('%s %.3f (%d)' % (s['name'], s['grays_per_s'], s['heavy_first_frames']))")"
  done
  echo "$line"
}
sph="--eye 0,0,3 --look-at 0,0,0 --up 0,1,0 --fov 45"; room="--scene preprocess/bench/bench_room.json"
for r in 1 2; do for k in mega-fifo mega-heavy mega; do
  alone "teapot $k" primary,shadow,reflect4 $w/teapot.pool --kernel $k --max-bounces 1
  alone "default room $k" primary,shadow,reflect4,full4 --kernel $k
  alone "culled room $k" primary,shadow,reflect4,full4 $w/culled.pool $room --kernel $k
  alone "sphere10m $k" primary,shadow,reflect4 $w/s10.pool $sph --kernel $k
done; done
echo "ALL_DONE $((SECONDS - t0)) s"
