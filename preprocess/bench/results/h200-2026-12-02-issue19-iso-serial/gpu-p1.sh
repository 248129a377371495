#!/usr/bin/env bash
# Issue 19, preprocessing on the GPU host's 16 cores: where each step's time goes (phase timings).
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/p1.txt") 2>&1
nproc; grep -m1 "model name" /proc/cpuinfo; nvidia-smi --query-gpu=name --format=csv,noheader
TIMEFORMAT="wall %R user %U sys %S"; b=$PWD/build-ab/cur; mkdir -p /tmp/bb/bin; cp $b/* /tmp/bb/bin/
BACKEND=auto KEEP=1 bash scripts/bench-preprocess.sh /tmp/bb 1000000 2,16 2 | tee /tmp/chain.txt
w=$(awk '/^# work folder:/{print $4}' /tmp/chain.txt); cd $w
for t in 16 8 4 2; do for r in 1 2; do echo "== prt-iso threads $t"; time taskset -c 0-$((t-1)) $b/prt-iso prt-cull.pool -o /tmp/i.pool --threads $t 2>&1 | grep -E "total|wall"; done; done
for be in cpu cuda; do for r in 1 2; do echo "== prt-cull $be 16"; time $b/prt-cull prt-octree.pool -o /tmp/c.pool --backend $be 2>&1 | tail -4; done; done
for be in cpu cuda; do for r in 1 2; do echo "== prt-radii $be 16"; time $b/prt-radii prt-import.pool -o /tmp/r.pool --backend $be 2>&1 | tail -3; done; done
for r in 1 2; do echo "== prt-octree 16"; time $b/prt-octree prt-radii.pool -o /tmp/o.pool 2>&1 | tail -4; done
for r in 1 2; do echo "== prt-import 16"; time $b/prt-import room.ply -o /tmp/m.pool 2>&1 | tail -4; done
echo ALL_DONE
