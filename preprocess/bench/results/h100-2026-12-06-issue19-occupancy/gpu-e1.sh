#!/usr/bin/env bash
# Issue 19 (e1): occupancy of the kernels whose targets are short. prt-bench built with
# -DPRT_CUDA_TUNING_KERNELS=ON (main de4ba08 + the plain ISO walk's variants at 2 and 4 blocks per
# SM; build-ab/e1.tar.xz), each scenario alone, 1024x1024, median of 100 frames after 10, two
# rounds: the culled 10M sphere's ISO primary (plain walk at 2 / 3 / 4, the regions' walk at 3,
# auto), its splats' primary at 2-5 blocks and the culled room's splats at 3-5. Then prt-cull
# (main, --backend cuda) on 2, 4, 8 and 16 cores with its own report: why 16 cores are slower.
# Carried: build-ab/tools5.tar.xz (main's tools for the pools), build-ab/e1.tar.xz.
NAME=e1 TARS="tools5.tar.xz e1.tar.xz"
source preprocess/bench/results/h100-2026-12-05-issue17-radii-neighbours/lib500.sh
source preprocess/bench/results/h100-2026-12-06-issue19-region-axes/alone.sh
x=$kall; q=--quiet; nb=/tmp/ab/e1/prt-bench; AL_LEAVES=1  # al(): alone.sh
cp $nb $kall/
make_pools $x
echo "pools done $((SECONDS - t0)) s"
sph="--eye 0,0,3 --look-at 0,0,0 --up 0,1,0 --fov 45"; room="--scene preprocess/bench/bench_room.json"
for r in 1 2; do
  for mb in 2 3 4; do al "r$r ISO 10M sphere, plain, $mb blocks:" primary $w/is10.pool $sph --surface iso --iso-walk plain --min-blocks $mb; done
  al "r$r ISO 10M sphere, regions, 3 blocks:" primary $w/is10.pool $sph --surface iso --iso-walk regions
  al "r$r ISO 10M sphere, auto (default):" primary,shadow $w/is10.pool $sph --surface iso
  for mb in 2 3 4 5; do al "r$r splats culled 10M sphere, $mb blocks:" primary $w/cs10.pool $sph --min-blocks $mb; done
  for mb in 3 4 5; do al "r$r splats culled room (bench_room.json), $mb blocks:" primary $w/croom.pool $room --min-blocks $mb; done
  echo "round $r done $((SECONDS - t0)) s"
done
for cores in 0-1 0-3 0-7 0-15 0-1 0-15; do
  for r in 1 2; do
    rm -f $w/c.pool
    /usr/bin/time -f "%e s wall, %U user, %S sys" taskset -c $cores $x/prt-cull $w/room.pool -o $w/c.pool --backend cuda 2> $w/cull.txt
    echo "cull cores $cores: $(grep -E 'time|total|s wall' $w/cull.txt | tr '\n' ' ')"
  done
done
echo "ALL_DONE $((SECONDS - t0)) s"
