#!/bin/bash
# Issue 19, round C (all of this stop's changes): build the chain's tools at this commit (new) and at 2ebdf12 (old: cull.h,
# cull_build.cpp, iso_build.cpp, iso_morton.h carried in .device-deps/old_*), then the GPU tests
# of culling and the ISO (the CPU path's new probe-hit pass must keep what the CUDA path keeps).
set -uo pipefail
OUT=${OUT:-/tmp/out}
mkdir -p "$OUT"
exec > >(tee "$OUT/c.txt") 2>&1
nvidia-smi --query-gpu=name --format=csv,noheader
flags="-DCMAKE_PREFIX_PATH=$PWD/.device-deps/usr -DPRT_WITH_PCL=OFF -DPRT_WITH_OPENMESH=OFF -DPRT_WITH_OIIO=OFF -DPRT_WITH_PYTHON=OFF -DPRT_WITH_GLFW=OFF -DCMAKE_BUILD_TYPE=Release"
t0=$SECONDS
cmake -S . -B build-dev $flags >/tmp/c.cmake.txt 2>&1 &&
    cmake --build build-dev -j16 --target prt-import prt-radii prt-octree prt-cull prt-iso prt-info prt-synth prt_cull_gpu_tests prt_iso_gpu_tests >/tmp/c.build.txt 2>&1 ||
    { grep -E "error" -A3 /tmp/c.build.txt | head -30; exit 1; }
echo "build: $((SECONDS - t0)) s"
mkdir -p /tmp/new /tmp/old
cp build-dev/bin/prt-cull build-dev/bin/prt-iso /tmp/new/
mkdir -p /tmp/keep
for f in runtime/core/include/prt/core/cull.h preprocess/splat/cull_build.cpp preprocess/iso/iso_build.cpp preprocess/iso/iso_morton.h; do
    cp $f /tmp/keep/$(basename $f)
    cp .device-deps/old_$(basename $f) $f
done
cmake --build build-dev -j16 --target prt-cull prt-iso >/tmp/c.build2.txt 2>&1 || { grep error -A3 /tmp/c.build2.txt | head; }
cp build-dev/bin/prt-cull build-dev/bin/prt-iso /tmp/old/
for f in runtime/core/include/prt/core/cull.h preprocess/splat/cull_build.cpp preprocess/iso/iso_build.cpp preprocess/iso/iso_morton.h; do
    cp /tmp/keep/$(basename $f) $f
done
cmake --build build-dev -j16 --target prt-cull prt-iso >/tmp/c.build3.txt 2>&1 || { grep error -A3 /tmp/c.build3.txt | head; }
cmp build-dev/bin/prt-cull /tmp/new/prt-cull && echo "new binaries restored"
echo "old build: $((SECONDS - t0)) s"
cd build-dev && ctest -R "CullGpu|IsoGpu" 2>&1 | grep -E "Test +#|tests passed|Skipped|Failed"
