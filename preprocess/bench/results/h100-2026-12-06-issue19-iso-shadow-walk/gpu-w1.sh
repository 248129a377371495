#!/usr/bin/env bash
# Issue 19 (w1): the ISO kernel for frames with shadow rays and no secondary ray (closest hits and
# shadow rays in one walk loop, core::k_mask_shadow_walk) against main's prt-bench (4d6d741),
# alternating, each scenario alone, two rounds; then every GPU test program of this build.
# Carried: build-ab/kall.tar.xz (this tree's tools and GPU test programs, kall/),
# build-ab/main-prt-bench.xz (main's), build-ab/bezier.
NAME=w1 TARS=kall.tar.xz
source preprocess/bench/results/h100-2026-12-05-issue17-radii-neighbours/lib500.sh
x=$kall; q=--quiet
$x/prt-bench --backend cuda --save-pool $w/room.pool --frames 1 --warmup 0 --scenarios primary $q > /dev/null 2>&1
$x/prt-cull $w/room.pool -o $w/croom.pool $q && $x/prt-iso $w/croom.pool -o $w/iroom.pool $q
$x/prt-synth sphere -n 10000000 -o $w/s10.pool $q && $x/prt-radii $w/s10.pool -o $w/s10.pool --backend cuda $q \
  && $x/prt-octree $w/s10.pool -o $w/s10.pool $q && $x/prt-cull $w/s10.pool -o $w/cs10.pool $q \
  && $x/prt-iso $w/cs10.pool -o $w/is10.pool $q
echo "pools done $((SECONDS - t0)) s"
xz -dc build-ab/main-prt-bench.xz > /tmp/prt-bench-main && chmod +x /tmp/prt-bench-main
alone() {  # alone LABEL BINARY SCENARIOS ARGS...: each scenario in its own process
  local label=$1 bin=$2 scs=$3; shift 3; local line="$label"
  for sc in ${scs//,/ }; do
    $bin --backend cuda --frames 30 --warmup 5 --json $w/b.json "$@" --scenarios $sc > /dev/null 2> $w/err.txt \
      || { line="$line $sc failed: $(tail -1 $w/err.txt)"; continue; }
    line="$line $(python3 -c "import json; s=json.load(open('$w/b.json'))['scenarios'][0]; print('%s %.3f [%.1f l]' % (s['name'], s['grays_per_s'], s['leaves_per_ray']))")"
  done
  echo "$line"
}
sph="--eye 0,0,3 --look-at 0,0,0 --up 0,1,0 --fov 45"; room="--scene preprocess/bench/bench_room.json"
for r in 1 2; do
  for cfg in main new; do
    b=$x/prt-bench; [ $cfg = main ] && b=/tmp/prt-bench-main
    alone "r$r iso culled room (pool's view), $cfg" $b primary,shadow,reflect4,full4 $w/iroom.pool --surface iso
    alone "r$r iso culled room (bench_room.json), $cfg" $b primary,shadow,full4 $w/iroom.pool $room --surface iso
    alone "r$r iso sphere10m, $cfg" $b primary,shadow,full4 $w/is10.pool $sph --surface iso
    alone "r$r splats culled room (bench_room.json), $cfg" $b primary,shadow $w/croom.pool $room
  done
done
echo "bench done $((SECONDS - t0)) s"
gpu_tests
echo "ALL_DONE $((SECONDS - t0)) s"
