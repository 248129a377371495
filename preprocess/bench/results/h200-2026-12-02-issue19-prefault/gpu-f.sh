#!/usr/bin/env bash
# Issue 19 on the GPU host (one H200, 16 Intel Xeon cores), 2026-12-02: this stop's whole change to
# the preprocessing chain (first touches in parallel, prt-cull's context on a thread, prt-import's
# clean() in parallel, mapped sections paged in by every core before their checksum) (new) against
# the landed tree (base: build-ab/base-src.tar.gz, git archive c4d7ce6). Both built here with CUDA 13
# for sm_90; the chain as a GPU-host user runs it (BACKEND=auto), the two alternating; pools
# compared section by section. Also: how long fsync of a 175 MB file takes on this host's /tmp.
# Usage (repository root, .device-deps and build-ab carried): bash <this script>
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/f1.txt") 2>&1
nproc; grep -m1 "model name" /proc/cpuinfo; nvidia-smi --query-gpu=name --format=csv,noheader
t0=$SECONDS; root=$PWD
mkdir -p /tmp/base && tar -xzf build-ab/base-src.tar.gz -C /tmp/base
tools="prt-import prt-radii prt-octree prt-cull prt-iso prt-info"
for v in new base; do
  src=$root; [ $v = base ] && src=/tmp/base
  cmake -S $src -B /tmp/b-$v -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$root/.device-deps/usr -DPRT_BUILD_TESTS=OFF \
    -DCMAKE_CUDA_ARCHITECTURES=90 >/tmp/cfg-$v.log 2>&1 && cmake --build /tmp/b-$v -j 16 --target $tools >/tmp/b-$v.log 2>&1 ||
    { echo "$v build failed"; tail -30 /tmp/b-$v.log; exit 1; }
  echo "$v build done $((SECONDS - t0)) s"
done
for r in 1 2; do for v in base new; do
  echo "== chain, auto, $v, round $r"
  BACKEND=auto KEEP=1 bash scripts/bench-preprocess.sh /tmp/b-$v 1000000 2,16 2 | tee /tmp/chain-$v.txt
done; done
hashes() {  # section name:sha1 of pool $1, provenance aside
  /tmp/b-new/bin/prt-info --json "$1" | python3 -c "
import json, sys, hashlib
d = json.load(sys.stdin); f = open('$1', 'rb'); out = []
for s in d['sections']:
    if s['name'] == 'provenance': continue
    f.seek(s['offset']); out.append(s['name'] + ':' + hashlib.sha1(f.read(s['bytes'])).hexdigest()[:12])
print(' '.join(out))"; }
wb=$(awk '/^# work folder:/{print $4}' /tmp/chain-base.txt); wn=$(awk '/^# work folder:/{print $4}' /tmp/chain-new.txt)
for s in prt-import prt-radii prt-octree prt-cull prt-iso; do
  if [ "$(hashes $wb/$s.pool)" = "$(hashes $wn/$s.pool)" ]; then echo "chain $s: pools equal section by section"
  else echo "chain $s: POOLS DIFFER"; fi
done
python3 -c "
import os, time
b = os.urandom(1 << 20) * 175
for r in range(2):
    t = time.time(); f = open('/tmp/fsync.bin', 'wb'); f.write(b); t1 = time.time(); f.flush(); os.fsync(f.fileno()); t2 = time.time(); f.close()
    print('175 MB: write %.3f s, fsync %.3f s' % (t1 - t, t2 - t1)); os.remove('/tmp/fsync.bin')"
echo "ALL_DONE $((SECONDS - t0)) s"
