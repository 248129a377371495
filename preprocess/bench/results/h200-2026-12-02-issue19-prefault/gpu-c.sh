#!/usr/bin/env bash
# Issue 19 on the GPU host (one H200, 16 Intel Xeon cores), 2026-12-02: prt-cull creates the GPU's
# context on a thread while it reads its input (pre::warm_up_cull_backend) (new) against prt-cull
# without it (base: this tree with build-ab/cull-warmup.patch reversed), both built here with CUDA
# 13 for sm_90; then this tree's GPU suites (ctest -L gpu). The two prt-cull binaries alternate on
# the chain's 1M-room octree pool (scripts/bench-preprocess.sh, BACKEND=auto, KEEP=1); pools are
# compared section by section.
# Usage (repository root, .device-deps and build-ab carried): bash <this script>
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/c1.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; t0=$SECONDS; root=$PWD
cmake -S . -B /tmp/bg -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$root/.device-deps/usr -DPRT_WITH_PCL=OFF \
  -DPRT_WITH_OPENMESH=OFF -DPRT_WITH_OIIO=OFF -DPRT_WITH_GLFW=OFF -DPRT_WITH_EMBREE=OFF -DCMAKE_CUDA_ARCHITECTURES=90 \
  > $out/configure.log 2>&1 && cmake --build /tmp/bg -j 16 > $out/build.log 2>&1 || { echo "build failed"; tail -30 $out/build.log; }
echo "build done $((SECONDS - t0)) s"
mkdir -p /tmp/base && tar --exclude=./build-ab --exclude=./.device-deps -cf - . | tar -xf - -C /tmp/base
(cd /tmp/base && patch -s -R -p1 < $root/build-ab/cull-warmup.patch) || { echo "patch failed"; exit 1; }
cmake -S /tmp/base -B /tmp/bb -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$root/.device-deps/usr -DPRT_BUILD_TESTS=OFF \
  -DCMAKE_CUDA_ARCHITECTURES=90 > /tmp/cfgb.log 2>&1 && cmake --build /tmp/bb -j 16 --target prt-cull > /tmp/bb.log 2>&1 ||
  { echo "base build failed"; tail -30 /tmp/bb.log; }
echo "base build done $((SECONDS - t0)) s"
ctest --test-dir /tmp/bg -L gpu --output-on-failure --timeout 300 > $out/gpu-tests.log 2>&1
grep -E "tests passed|tests failed|Failed|\(Skipped\)|Not Run" $out/gpu-tests.log | head -30
echo "gpu tests done $((SECONDS - t0)) s"
BACKEND=auto KEEP=1 bash scripts/bench-preprocess.sh /tmp/bg 1000000 16 1 | tee /tmp/chain.txt
w=$(awk '/^# work folder:/{print $4}' /tmp/chain.txt)
for t in 2 16; do for r in 1 2 3 4; do for v in base new; do
  b=/tmp/bg/bin/prt-cull; [ $v = base ] && b=/tmp/bb/bin/prt-cull
  s0=$(date +%s.%N)
  taskset -c 0-$((t - 1)) $b $w/prt-octree.pool -o /tmp/cull-$v.pool -q --backend auto --stats-json /tmp/cull-$v.json
  s1=$(date +%s.%N)
  python3 -c "import json; j=json.load(open('/tmp/cull-$v.json')); print('prt-cull $v ${t}thr r$r wall %.3f' % ($s1 - $s0), j['device'], 'cull %.3f total %.3f' % (j['cull_seconds'], j['total_seconds']))"
done; done; done
python3 - <<'PY'
import sys; sys.path.insert(0, 'scripts/lib'); import prt_provenance as p
a = p.read_checksums('/tmp/cull-base.pool'); b = p.read_checksums('/tmp/cull-new.pool')
print('prt-cull pools equal section by section:', all(a[k] == b.get(k) for k in a if k != 1), len(a), 'sections')
PY
echo "ALL_DONE $((SECONDS - t0)) s"
