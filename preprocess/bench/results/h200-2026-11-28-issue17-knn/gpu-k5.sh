#!/usr/bin/env bash
# Issue 19: the 1M-point preprocessing chain (scripts/bench-preprocess.sh) on 2 and 16 cores of the
# GPU host, BACKEND=cpu (the cores alone) and BACKEND=auto (what a user of the GPU host gets: prt-radii
# on the GPU from 100k points per thread, so on 2 cores and not on 16; prt-cull on the GPU).
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"
exec > >(tee -a "$out/k5.txt") 2>&1
deps="-DCMAKE_PREFIX_PATH=$PWD/.device-deps/usr -DPRT_WITH_PCL=OFF -DPRT_WITH_OPENMESH=OFF -DPRT_WITH_OIIO=OFF -DPRT_WITH_PYTHON=OFF -DPRT_WITH_GLFW=OFF -DCMAKE_BUILD_TYPE=Release"
s0=$(date +%s)
cmake -S . -B build-dev $deps > /tmp/cmake.txt 2>&1 || tail -5 /tmp/cmake.txt
cmake --build build-dev -j16 --target prt-import prt-radii prt-octree prt-cull prt-iso > /tmp/build1.txt 2>&1 || grep -E "error" /tmp/build1.txt | head
echo "built: $(( $(date +%s) - s0 )) s"
for b in auto cpu; do BACKEND=$b bash scripts/bench-preprocess.sh build-dev 1000000 2,16 2; done
