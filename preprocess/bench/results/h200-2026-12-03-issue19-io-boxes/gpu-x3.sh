#!/usr/bin/env bash
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/x3.txt") 2>&1
nvidia-smi --query-gpu=name --format=csv,noheader
root=$PWD; b=$root/build-ab/nb; mkdir -p /tmp/w; cd /tmp/w
$b/prt-bench --backend cuda --synthetic 1000000 --save-pool room.pool --frames 1 --warmup 0 --width 16 --height 16 --scenarios primary --quiet >/dev/null
$b/prt-cull room.pool -o room_c.pool --quiet
sed 's/"room.pool"/"room_c.pool"/' $root/preprocess/bench/bench_room.json > scene_c.json
for r in 1 2; do for env in X=1 PRT_NODE_BOXES=1; do
  echo "== culled room $env"; env $env $b/prt-bench --backend cuda room_c.pool --scene scene_c.json --frames 30 --warmup 5 --scenarios primary,shadow,reflect4,full4 --quiet | grep -E "^(primary|shadow|reflect4|full4) "
  echo "== default room (unculled) $env"; env $env $b/prt-bench --backend cuda --frames 30 --warmup 5 --scenarios primary,shadow,reflect4,full4 --quiet | grep -E "^(primary|shadow|reflect4|full4) "
done; done
for env in X=1 PRT_NODE_BOXES=1; do env $env $b/prt-play room_c.pool --scene scene_c.json --backend cuda --out img-$env.ppm --quiet; env $env $b/prt-play room.pool --scene $root/preprocess/bench/bench_room.json --backend cuda --out imgu-$env.ppm --quiet; done
ls -la *.ppm; cmp img-X=1.ppm img-PRT_NODE_BOXES=1.ppm && echo "culled images equal"; cmp imgu-X=1.ppm imgu-PRT_NODE_BOXES=1.ppm && echo "unculled images equal"
echo ALL_DONE
