#!/usr/bin/env bash
# Issue 19 (w4, experiment, not landed): the ISO kernels without secondary rays at 2, 3 and 4 blocks
# per SM (--min-blocks; an experiment binary with those variants compiled in), alternating, each
# scenario alone, two rounds: ISO primary and shadow on the three views.
NAME=w4 TARS=kall.tar.xz
source preprocess/bench/results/h100-2026-12-05-issue17-radii-neighbours/lib500.sh
source preprocess/bench/results/h100-2026-12-06-issue19-region-axes/alone.sh
make_pools $kall
echo "pools done $((SECONDS - t0)) s"
xz -dc build-ab/exp-prt-bench.xz > /tmp/prt-bench-exp && chmod +x /tmp/prt-bench-exp
b=/tmp/prt-bench-exp
sph="--eye 0,0,3 --look-at 0,0,0 --up 0,1,0 --fov 45"; room="--scene preprocess/bench/bench_room.json"
for r in 1 2; do
  for mb in 2 3 4; do
    alone "r$r iso culled room (pool's view), blocks $mb" $b primary,shadow $w/iroom.pool --surface iso --min-blocks $mb
    alone "r$r iso culled room (bench_room.json), blocks $mb" $b primary,shadow $w/iroom.pool $room --surface iso --min-blocks $mb
    alone "r$r iso sphere10m, blocks $mb" $b primary,shadow $w/is10.pool $sph --surface iso --min-blocks $mb
  done
done
echo "ALL_DONE $((SECONDS - t0)) s"
