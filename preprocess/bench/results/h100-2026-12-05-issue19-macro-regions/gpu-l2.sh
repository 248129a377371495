#!/usr/bin/env bash
# Issue 19 (l2): macro-regions (an empty leaf left through a box of free cells around it) in the
# splat walk. Every GPU test program of this tree; then prt-bench, each scenario alone in its own
# process, two rounds: node boxes and macro-regions on / off (PRT_NODE_BOXES, PRT_MACRO_REGIONS at
# load), the culled room (bench_room.json), the culled 10M sphere and prt-bench's own room; the leaf
# bounds' modes and a leaf size X = 64 on the culled room.
NAME=l2 TARS=kall.tar.xz
source preprocess/bench/results/h100-2026-12-05-issue17-radii-neighbours/lib500.sh
gpu_tests
x=$kall; q=--quiet
for X in 32 64; do
  $x/prt-bench --backend cuda --max-leaf $X --save-pool $w/room$X.pool --frames 1 --warmup 0 --scenarios primary $q > /dev/null 2>&1
  $x/prt-cull $w/room$X.pool -o $w/croom$X.pool $q
done
$x/prt-synth sphere -n 10000000 -o $w/s10.pool $q && $x/prt-radii $w/s10.pool -o $w/s10.pool --backend cuda $q \
  && $x/prt-octree $w/s10.pool -o $w/s10.pool $q && $x/prt-cull $w/s10.pool -o $w/cs10.pool $q
echo "pools done $((SECONDS - t0)) s"
alone() {  # alone LABEL SCENARIOS ARGS...: each scenario in its own process
  local label=$1 scs=$2; shift 2; local line="$label"
  for sc in ${scs//,/ }; do
    $x/prt-bench --backend cuda --frames 30 --warmup 5 --json $w/b.json "$@" --scenarios $sc > /dev/null 2> $w/err.txt \
      || { line="$line $sc failed: $(tail -1 $w/err.txt)"; continue; }
    line="$line $(python3 -c "import json; s=json.load(open('$w/b.json'))['scenarios'][0]; print('%s %.3f [%.1f l %.1f t]' % (s['name'], s['grays_per_s'], s['leaves_per_ray'], s['splat_tests_per_ray']))")"
  done
  echo "$line"
}
sph="--eye 0,0,3 --look-at 0,0,0 --up 0,1,0 --fov 45"; room="--scene preprocess/bench/bench_room.json"
for r in 1 2; do
  for cfg in "1 0" "1 1" "0 1"; do set -- $cfg; export PRT_NODE_BOXES=$1 PRT_MACRO_REGIONS=$2; k="boxes $1 regions $2"
    alone "r$r culled room, $k" primary,shadow,reflect4,full4 $w/croom32.pool $room
    alone "r$r sphere10m, $k" primary,shadow,reflect4 $w/cs10.pool $sph
    alone "r$r default room, $k" primary,shadow,reflect4,full4
    alone "r$r culled room X=64, $k" primary,shadow,reflect4,full4 $w/croom64.pool $room
  done
  export PRT_NODE_BOXES=1 PRT_MACRO_REGIONS=0
  for c in 1 0; do alone "r$r culled room, boxes 1 regions 0, leaf culling $c" primary,shadow,reflect4,full4 $w/croom32.pool $room --leaf-culling $c; done
done
unset PRT_NODE_BOXES PRT_MACRO_REGIONS
for reg in 0 1; do  # the scene's load (leaf bounds, node boxes, macro-regions) in prt-bench's wall time, one frame
  for i in 1 2; do /usr/bin/time -f "sphere10m load+1 frame, regions $reg: %e s wall" env PRT_MR_STATS=1 PRT_MACRO_REGIONS=$reg $x/prt-bench --backend cuda $w/cs10.pool $sph --frames 1 --warmup 0 --scenarios primary $q > /dev/null; done
done
echo "ALL_DONE $((SECONDS - t0)) s"
