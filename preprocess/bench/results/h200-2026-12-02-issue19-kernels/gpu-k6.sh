#!/usr/bin/env bash
# Issue 19 on the GPU host (one H200), 2026-12-02, fifth call: the committed tree (aadff08) built
# there with CUDA 13 (header-only deps from .device-deps/usr) and its whole GPU suite, ctest -L gpu.
# Usage (repository root): bash preprocess/bench/results/h200-2026-12-02-issue19-kernels/gpu-k6.sh
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/k6.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; t0=$SECONDS
cmake -S . -B build-gpu -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$PWD/.device-deps/usr -DPRT_WITH_PCL=OFF \
  -DPRT_WITH_OPENMESH=OFF -DPRT_WITH_OIIO=OFF -DPRT_WITH_GLFW=OFF -DPRT_WITH_EMBREE=OFF > $out/configure.log 2>&1 \
  && cmake --build build-gpu -j 16 > $out/build.log 2>&1 || { echo "build failed"; grep -m20 -E "error" $out/build.log; }
echo "build done $((SECONDS - t0)) s"
ctest --test-dir build-gpu -L gpu -j 4 --output-on-failure --timeout 150 > $out/gpu-tests-k6.log 2>&1
grep -E "tests passed|tests failed|Failed|\(Skipped\)|Not Run|Total Test time" $out/gpu-tests-k6.log | head -30
echo "ALL_DONE $((SECONDS - t0)) s"
