#!/usr/bin/env bash
# Issue 19 (e4): with the splat kernels at 3 blocks per SM (more registers), do node boxes pay again?
# The e3 build (build-ab/k2.tar.xz), --empty-space regions (default) / both / boxes, each scenario
# alone, median of 100 frames after 10, two rounds. Then the culled 10M sphere's ISO and splat
# primary rays with the linear mapping, the queue in image order, and the driver's L1 carveout.
NAME=e4 TARS="k2.tar.xz"
source preprocess/bench/results/h100-2026-12-05-issue17-radii-neighbours/lib500.sh
source preprocess/bench/results/h100-2026-12-06-issue19-region-axes/alone.sh
x=$kall; q=--quiet; nb=$kall/prt-bench; AL_LEAVES=1  # al(): alone.sh
make_pools $x
make_sphere1 $x
echo "pools done $((SECONDS - t0)) s"
sph="--eye 0,0,3 --look-at 0,0,0 --up 0,1,0 --fov 45"; room="--scene preprocess/bench/bench_room.json"
for r in 1 2; do
  for es in regions both boxes; do
    al "r$r $es, splats, culled 10M sphere:" primary,shadow,reflect4 $w/cs10.pool $sph --empty-space $es
    al "r$r $es, splats, culled 1M sphere:" primary,shadow $w/cs1.pool $sph --empty-space $es
    al "r$r $es, splats, culled room:" primary,shadow,reflect4 $w/croom.pool $room --empty-space $es
  done
  for o in "" "--mapping linear" "--kernel mega-fifo" "--default-carveout"; do
    al "r$r ISO, culled 10M sphere, ${o:-defaults}:" primary $w/is10.pool $sph --surface iso $o
    al "r$r splats, culled 10M sphere, ${o:-defaults}:" primary $w/cs10.pool $sph $o
  done
  echo "round $r done $((SECONDS - t0)) s"
done
echo "ALL_DONE $((SECONDS - t0)) s"
