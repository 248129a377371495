#!/usr/bin/env bash
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/x1.txt") 2>&1
nproc; grep -m1 "model name" /proc/cpuinfo; nvidia-smi --query-gpu=name,persistence_mode --format=csv,noheader; df -T /tmp | tail -1; free -g | head -2
TIMEFORMAT="wall %R user %U sys %S"; e=$PWD/build-ab/exp
for r in 1 2 3; do for m in normal _exit free_exit reset drv; do time $e/ctx $m; done; done
for r in 1 2 3 4; do for m in plain range range_nowait nosync; do $e/wb /tmp 175 $m; done; done
for r in 1 2; do for m in plain range_nowait; do $e/wb /tmp 150 $m 32; done; done
b=$PWD/build-ab/cur; mkdir -p /tmp/bb/bin; cp $b/* /tmp/bb/bin/
BACKEND=auto KEEP=1 bash scripts/bench-preprocess.sh /tmp/bb 1000000 16 3 | tee /tmp/chain.txt
w=$(awk '/^# work folder:/{print $4}' /tmp/chain.txt); cd $w
for r in 1 2 3; do echo "== prt-cull cuda 16"; time $b/prt-cull prt-octree.pool -o /tmp/c.pool --backend cuda 2>&1 | tail -1; done
echo ALL_DONE
