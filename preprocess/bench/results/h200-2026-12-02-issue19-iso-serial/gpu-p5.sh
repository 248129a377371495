#!/usr/bin/env bash
# Issue 19 on the GPU host (one H200, 16 Intel Xeon cores), 2026-12-02: the final prt-iso (commits 444e06c,
# 27289fe and its corner blocks and leaf slots in parallel; built in the dev VM's CUDA build) against the landed prt-iso
# (base); the other tools the landed ones (built on the dev VM). The chain as a GPU-host user runs
# it (BACKEND=auto), two alternating rounds; prt-iso alone at 16 and 2 threads; pools compared.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/p5.txt") 2>&1
nproc; grep -m1 "model name" /proc/cpuinfo; nvidia-smi --query-gpu=name --format=csv,noheader
root=$PWD
echo "== prt_iso_gpu_tests"; timeout 200 build-ab/tests/prt_iso_gpu_tests > $out/prt_iso_gpu_tests.log 2>&1; echo "rc $? $(grep -E "^\[  (PASSED|FAILED|SKIPPED) " $out/prt_iso_gpu_tests.log | tr "\n" " ")"
for v in base new; do mkdir -p /tmp/b-$v/bin; done
cp build-ab/cur/* /tmp/b-base/bin/; cp build-ab/new/* /tmp/b-new/bin/
for r in 1 2; do for v in base new; do
  echo "== chain, auto, $v, round $r"
  BACKEND=auto KEEP=1 bash scripts/bench-preprocess.sh /tmp/b-$v 1000000 2,16 2 | tee /tmp/chain-$v.txt
done; done
w=$(awk '/^# work folder:/{print $4}' /tmp/chain-new.txt); cd $w
for r in 1 2 3; do for v in base new; do for t in 16 2; do
  echo "== prt-iso $v threads $t"; taskset -c 0-$((t-1)) /tmp/b-$v/bin/prt-iso prt-cull.pool -o /tmp/i-$v.pool --threads $t 2>&1 | grep total
done; done; done
hashes() { /tmp/b-new/bin/prt-info --json "$1" | python3 -c "
import json, sys, hashlib
d = json.load(sys.stdin); f = open('$1', 'rb'); out = []
for s in d['sections']:
    if s['name'] == 'provenance': continue
    f.seek(s['offset']); out.append(s['name'] + ':' + hashlib.sha1(f.read(s['bytes'])).hexdigest()[:12])
print(' '.join(out))"; }
[ "$(hashes /tmp/i-base.pool)" = "$(hashes /tmp/i-new.pool)" ] && echo "prt-iso pools equal section by section" || echo "prt-iso POOLS DIFFER"
echo ALL_DONE
