#!/usr/bin/env bash
# Issue 19 (H200): heavy lists that keep their items (../h200-2026-12-04-issue19-timed-order, u4:
# lists inherited from another scenario settled richer and 6 % faster). Experiment build: an item
# handed out from the previous frame's lists stays listed while above PRT_HEAVY_KEEP x the mean item
# (2: off, the landed rule; 1; 0.5); every scenario alone in its own process, two rounds.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/v1.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; t0=$SECONDS
rm -rf /tmp/ab; mkdir -p /tmp/ab
python3 -c "import tarfile; tarfile.open('build-ab/pack.tar.xz').extractall('/tmp/ab')"
x=/tmp/ab/bin; w=/tmp/v1; mkdir -p $w; q=--quiet
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
    line="$line $(python3 -c "import json; s=json.load(open('$w/b.json'))['scenarios'][0]; h=s['frames_heavy_first_items']; print('%s %.3f (%d)' % (s['name'], s['grays_per_s'], sorted(h)[len(h)//2]))")"
  done
  echo "$line"
}
sph="--eye 0,0,3 --look-at 0,0,0 --up 0,1,0 --fov 45"; room="--scene preprocess/bench/bench_room.json"
for r in 1 2; do for k in 2 1 0.5; do
  export PRT_HEAVY_KEEP=$k
  alone "teapot keep $k" primary,shadow,reflect4 $w/teapot.pool --max-bounces 1
  alone "room.pool keep $k" primary,shadow,reflect4,full4 $w/room.pool
  alone "culled room keep $k" primary,shadow,reflect4,full4 $w/culled.pool $room
  alone "sphere10m keep $k" primary,shadow,reflect4 $w/s10.pool $sph
done; done
echo "ALL_DONE $((SECONDS - t0)) s"
