#!/usr/bin/env bash
# Issue 19 (e2): the splat kernels at 3 blocks per SM against the default 4 (e1: the culled room's
# primary rays 2.11 -> 2.70 Grays/s at 3). The same tuning build as e1 (build-ab/e1.tar.xz);
# --min-blocks picks both splat kernels' variant (with and without secondary rays). Each scenario
# alone, 1024x1024, median of 100 frames after 10; two rounds, the two occupancies alternating.
NAME=e2 TARS="tools5.tar.xz e1.tar.xz"
source preprocess/bench/results/h100-2026-12-05-issue17-radii-neighbours/lib500.sh
source preprocess/bench/results/h100-2026-12-06-issue19-region-axes/alone.sh
x=$kall; q=--quiet; nb=/tmp/ab/e1/prt-bench  # al(): alone.sh
cp $nb $kall/
make_pools $x
make_sphere1 $x
echo "pools done $((SECONDS - t0)) s"
sph="--eye 0,0,3 --look-at 0,0,0 --up 0,1,0 --fov 45"; room="--scene preprocess/bench/bench_room.json"
S=primary,shadow,reflect4,full4
for r in 1 2; do
  for mb in 4 3; do
    al "r$r $mb blocks, splats, culled room (bench_room.json):" $S $w/croom.pool $room --min-blocks $mb
    al "r$r $mb blocks, splats, prt-bench's room:" $S --min-blocks $mb
    al "r$r $mb blocks, splats, culled 1M sphere:" primary,shadow,reflect4 $w/cs1.pool $sph --min-blocks $mb
    al "r$r $mb blocks, splats, 1M sphere not culled:" primary,shadow $w/s1.pool $sph --min-blocks $mb
    al "r$r $mb blocks, splats, culled 10M sphere:" $S $w/cs10.pool $sph --min-blocks $mb
    al "r$r $mb blocks, splats, 10M sphere not culled:" primary,shadow $w/s10.pool $sph --min-blocks $mb
  done
  echo "round $r done $((SECONDS - t0)) s"
done
al "2 blocks, splats, culled room (bench_room.json):" reflect4,full4 $w/croom.pool $room --min-blocks 2
al "2 blocks, splats, culled 10M sphere:" reflect4,full4 $w/cs10.pool $sph --min-blocks 2
echo "ALL_DONE $((SECONDS - t0)) s"
