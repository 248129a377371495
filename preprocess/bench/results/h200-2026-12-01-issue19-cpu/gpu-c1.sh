#!/usr/bin/env bash
# Issue 19 on the GPU host (one H200, 16 cores), 2026-12-01: the CPU backend against Embree 3 on the
# host's cores, 16 and 2 (taskset), on prt-bench's 1M room after prt-cull, the tree before this
# change (base: cfeef3b's core with this tree's prt-bench-embree, whose two renderers take turns frame
# by frame) against this one, alternating.
# gpu-c2.sh then builds the tree there with CUDA and runs its GPU suites.
# Carried in .eb/ (built on the dev VM, CPU only, build-dev): bin/prt-bench, bin/prt-cull,
# bin/prt-bench-embree (this tree), bin/base-embree, lib.tar.xz (Debian 12's libembree3.so.3
# and libtbb.so.12: the GPU host has no Embree).
# Usage (repository root): bash preprocess/bench/results/h200-2026-12-01-issue19-cpu/gpu-c1.sh
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/c1.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; nproc; grep -m1 "model name" /proc/cpuinfo
t0=$SECONDS; root=$PWD; w=/tmp/w; mkdir -p $w/json; tar xJf .eb/lib.tar.xz -C $w; export LD_LIBRARY_PATH=$w/lib
eb=$root/.eb/bin; cd $w
$eb/prt-bench --backend cpu --synthetic 1000000 --save-pool room.pool --frames 1 --warmup 0 --width 64 --height 64 \
  --scenarios primary --quiet >/dev/null && $eb/prt-cull room.pool -o room_c.pool --quiet || echo "pool failed"
sed 's/"room.pool"/"room_c.pool"/' $root/preprocess/bench/bench_room.json > scene.json
run() {  # label, binary, threads, size, taskset cpus
  local pre=""; [ -n "$5" ] && pre="taskset -c $5"
  echo -n "$1 th=$3 $4: "
  $pre $2 room_c.pool --scene scene.json --width $4 --height $4 --frames 5 --warmup 1 --threads $3 --quiet \
    --json $w/json/$1-$3-$4-$6.json 2>&1 | awk '/^(primary|shadow|reflect4) +[0-9]/{printf "%s %s/%s ms r=%s  ", $1, $2, $3, $6}'
  echo
}
for r in 1 2; do
  for sz in 512 1024; do
    run base $eb/base-embree 16 $sz "" r$r; run new $eb/prt-bench-embree 16 $sz "" r$r
  done
  run base $eb/base-embree 2 512 0,1 r$r; run new $eb/prt-bench-embree 2 512 0,1 r$r
done
tar czf $out/c1-json.tgz -C $w json
echo "embree done $((SECONDS - t0)) s"
echo "ALL_DONE $((SECONDS - t0)) s"
