#!/usr/bin/env bash
# This tree built on the GPU host (one H200) with CUDA 13 for sm_90, in the reduced configuration
# that host allows (no PCL, OpenMesh, OIIO, GLFW, Embree); its GPU suites (ctest -L gpu), then the
# CPU tests of the code this change touched (buffer.h, prt-iso, prt-octree and what builds on
# them: bricks, culling). Usage (repository root, .device-deps carried): bash <this script>
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/tests.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; t0=$SECONDS
cmake -S . -B /tmp/bg -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$PWD/.device-deps/usr -DPRT_WITH_PCL=OFF \
  -DPRT_WITH_OPENMESH=OFF -DPRT_WITH_OIIO=OFF -DPRT_WITH_GLFW=OFF -DPRT_WITH_EMBREE=OFF > $out/configure.log 2>&1 \
  && cmake --build /tmp/bg -j 16 > $out/build.log 2>&1 || { echo "build failed"; tail -30 $out/build.log; }
echo "build done $((SECONDS - t0)) s"
ctest --test-dir /tmp/bg -L gpu --output-on-failure --timeout 300 > $out/gpu-tests.log 2>&1
grep -E "tests passed|tests failed|Failed|\(Skipped\)|Not Run" $out/gpu-tests.log | head -30
echo "gpu tests done $((SECONDS - t0)) s"
ctest --test-dir /tmp/bg -L cpu -LE slow -R "LargeMemory|Iso|Octree|Brick|Cull|Radix" -j 16 --timeout 300 > $out/cpu-tests.log 2>&1
grep -E "tests passed|tests failed|\(Failed\)|Not Run" $out/cpu-tests.log | head -30
echo "ALL_DONE $((SECONDS - t0)) s"
