#!/usr/bin/env bash
# Issue 19 (w2): three macro-regions per empty leaf, each grown along one axis first, the ray's
# major axis picking one (and halving steps up to the obstacle), against main's prt-bench (4d6d741,
# one box grown every way in turn), alternating, each scenario alone, two rounds; the wall time of
# a one-frame run (load, regions, one frame); then every GPU test program of this build.
# Carried: build-ab/kall.tar.xz (this tree, kall/), build-ab/main-prt-bench.xz, build-ab/bezier.
NAME=w2 TARS=kall.tar.xz
source preprocess/bench/results/h100-2026-12-05-issue17-radii-neighbours/lib500.sh
source preprocess/bench/results/h100-2026-12-06-issue19-region-axes/alone.sh
x=$kall
make_pools $x
echo "pools done $((SECONDS - t0)) s"
xz -dc build-ab/main-prt-bench.xz > /tmp/prt-bench-main && chmod +x /tmp/prt-bench-main
sph="--eye 0,0,3 --look-at 0,0,0 --up 0,1,0 --fov 45"; room="--scene preprocess/bench/bench_room.json"
for r in 1 2; do
  for cfg in main new; do
    b=$x/prt-bench; [ $cfg = main ] && b=/tmp/prt-bench-main
    alone "r$r splats prt-bench room, $cfg" $b primary,shadow,reflect4,full4
    alone "r$r splats culled room (bench_room.json), $cfg" $b primary,shadow,reflect4,full4 $w/croom.pool $room
    alone "r$r splats culled 10M sphere, $cfg" $b primary,shadow,reflect4 $w/cs10.pool $sph
    alone "r$r iso culled room (pool's view), $cfg" $b primary,shadow,full4 $w/iroom.pool --surface iso
    alone "r$r iso culled room (bench_room.json), $cfg" $b primary,full4 $w/iroom.pool $room --surface iso
    alone "r$r iso sphere10m, $cfg" $b primary,shadow,full4 $w/is10.pool $sph --surface iso
  done
done
echo "bench done $((SECONDS - t0)) s"
for cfg in main new; do
  b=$x/prt-bench; [ $cfg = main ] && b=/tmp/prt-bench-main
  for p in "$w/croom.pool" "$w/is10.pool --surface iso" "$w/iroom.pool --surface iso"; do
    s=$SECONDS; /usr/bin/time -f "%e s wall" $b $p --backend cuda --frames 1 --warmup 0 --scenarios primary --quiet > /dev/null 2> $w/t.txt
    echo "one-frame run $cfg $p: $(tail -1 $w/t.txt)"
  done
done
gpu_tests
echo "ALL_DONE $((SECONDS - t0)) s"
