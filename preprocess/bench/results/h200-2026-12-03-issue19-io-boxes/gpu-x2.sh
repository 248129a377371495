#!/usr/bin/env bash
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/x2.txt") 2>&1
nproc; grep -m1 "model name" /proc/cpuinfo; nvidia-smi --query-gpu=name --format=csv,noheader
TIMEFORMAT="wall %R user %U sys %S"; ab=$PWD/build-ab; root=$PWD
export PRTINFO=$ab/new/prt-info
echo "== prt_cull_gpu_tests"
mkdir -p /work/main/build-cu/bin && cp $ab/new/prt-cull /work/main/build-cu/bin/ && $ab/tests/prt_cull_gpu_tests 2>&1 | tail -15
for v in cur new; do mkdir -p /tmp/$v/bin; cp $ab/$v/* /tmp/$v/bin/; done
for r in 1 2 3; do for v in cur new; do echo "== chain 16 $v round $r"; BACKEND=auto KEEP=1 bash scripts/bench-preprocess.sh /tmp/$v 1000000 16 2 | tee /tmp/chain-$v.txt | sed -n '/^step/,$p'; done; done
wc=$(awk '/^# work folder:/{print $4}' /tmp/chain-cur.txt); wn=$(awk '/^# work folder:/{print $4}' /tmp/chain-new.txt)
for s in prt-import prt-radii prt-octree prt-cull prt-iso; do a=$(bash $ab/poolhash.sh $wc/$s.pool); b=$(bash $ab/poolhash.sh $wn/$s.pool); [ "$a" = "$b" ] && echo "$s pools equal" || echo "$s POOLS DIFFER: $a / $b"; done
cd $wc
for r in 1 2 3 4; do for v in cur new; do echo "== prt-cull cuda $v"; time /tmp/$v/bin/prt-cull prt-octree.pool -o /tmp/c-$v.pool --backend cuda 2>&1 | tail -1; done; done
for r in 1 2 3; do for v in cur new; do echo "== prt-octree $v"; time /tmp/$v/bin/prt-octree prt-radii.pool -o /tmp/o-$v.pool 2>&1 | tail -1; echo "== prt-iso $v"; time /tmp/$v/bin/prt-iso prt-cull.pool -o /tmp/i-$v.pool 2>&1 | tail -1; done; done
cd $root
for r in 1; do for v in cur new; do echo "== chain 2 $v"; BACKEND=auto bash scripts/bench-preprocess.sh /tmp/$v 1000000 2 1 | sed -n '/^step/,$p'; done; done
echo ALL_DONE
