#!/usr/bin/env bash
# After merging issue 20/21 work: the gpu-labelled tests (photons from area lights on the GPU among them).
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"
exec > >(tee -a "$out/log20.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
s0=$(date +%s)
R=/tmp/xroot; mkdir -p $R && tar -C $R -xJf .gl/gl-root.tar.xz
export LD_LIBRARY_PATH=$R/usr/lib/x86_64-linux-gnu${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
cmake -S . -B build-dev "-DCMAKE_PREFIX_PATH=$PWD/.device-deps/usr;$R/usr" -DPRT_WITH_GLFW=ON -DPRT_WITH_PCL=OFF -DPRT_WITH_OPENMESH=OFF -DPRT_WITH_OIIO=OFF -DPRT_WITH_PYTHON=OFF -DCMAKE_BUILD_TYPE=Release > /tmp/cmake.txt 2>&1 || tail -5 /tmp/cmake.txt
cmake --build build-dev -j16 --target prt_brick_stream_gpu_tests prt_cull_gpu_tests prt_iso_gpu_tests prt_mls_gpu_tests prt_patches_gpu_tests prt_photons_gpu_tests prt_runtime_gpu_tests prt_stability_gpu_tests prt_window_gpu_tests prt-play >/tmp/build.txt 2>&1 || { grep -E "error" /tmp/build.txt | head -30; }
echo "build: $(( $(date +%s) - s0 )) s"
(cd build-dev && ../scripts/gpu-window.sh --root $R -- ctest -L gpu -j4 --timeout 200 --output-on-failure > "$out/ctest_gpu20.txt" 2>&1; grep -E "tests passed|\*\*\*|Failed|FAILED|Not Run" "$out/ctest_gpu20.txt" | head -12)
grep -E "AreaLight|Window" "$out/ctest_gpu20.txt" | grep -E "Passed|Failed|Skipped" | head
echo "ALL_DONE $(( $(date +%s) - s0 )) s"
