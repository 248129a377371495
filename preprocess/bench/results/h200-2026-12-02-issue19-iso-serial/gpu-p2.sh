#!/usr/bin/env bash
# Issue 19 on the GPU host, 2026-12-02: prt-iso's phases timed inside (iso-trace.patch applied to the
# landed iso_build.cpp, built on the dev VM, PRT_ISO_TRACE=1 prints the sums; not committed) at 16,
# 2, 16 and 8 threads on the chain's culled 1M room.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/p2.txt") 2>&1
b=$PWD/build-ab/cur; mkdir -p /tmp/bb/bin; cp $b/* /tmp/bb/bin/
BACKEND=auto KEEP=1 bash scripts/bench-preprocess.sh /tmp/bb 1000000 16 1 | tee /tmp/chain.txt
w=$(awk '/^# work folder:/{print $4}' /tmp/chain.txt); cd $w
for t in 16 2 16 8; do echo "== traced prt-iso threads $t"; PRT_ISO_TRACE=1 taskset -c 0-$((t-1)) $OLDPWD/build-ab/prt-iso-trace prt-cull.pool -o /tmp/i.pool --threads $t 2>&1 | grep -E "TRACE|total"; done
echo ALL_DONE
