#!/usr/bin/env bash
# Issue 20 on the GPU machine, second call: the gpu-labelled tests of the pieces this session touched
# (photons, light map, patches: prt-patches' orientation, the renderer over patches), and prt-photons'
# throughput end to end (upload and download included) on the glass-sphere sample scene at several
# photon counts (scripts/make-gi-samples.sh builds its pools).
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"
exec > >(tee -a "$out/log20p.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
s0=$(date +%s)
cmake -S . -B build-dev "-DCMAKE_PREFIX_PATH=$PWD/.device-deps/usr" -DPRT_WITH_PCL=OFF -DPRT_WITH_OPENMESH=OFF -DPRT_WITH_OIIO=OFF -DPRT_WITH_PYTHON=OFF -DPRT_WITH_GLFW=OFF -DCMAKE_BUILD_TYPE=Release > /tmp/cmake.txt 2>&1 || tail -5 /tmp/cmake.txt
cmake --build build-dev -j16 --target prt_lightmap_gpu_tests prt_photons_gpu_tests prt_patches_gpu_tests prt_runtime_gpu_tests prt-lightmap prt-photons prt-synth prt-radii prt-octree prt-iso prt-mls prt-patches prt-cull prt-play >/tmp/build.txt 2>&1 || { grep -E "error" /tmp/build.txt | head -30; }
echo "build: $(( $(date +%s) - s0 )) s"
(cd build-dev && ctest -L gpu -R "LightMapGpu|PhotonsGpu|Patch|Backend|Gpu" --timeout 300 --output-on-failure > "$out/ctest_gpu20p.txt" 2>&1; grep -E "tests passed|\*\*\*|Failed|FAILED|Not Run" "$out/ctest_gpu20p.txt" | head -20)
BUILD_DIR=$PWD/build-dev bash scripts/make-gi-samples.sh > /tmp/gi.txt 2>&1 || tail -5 /tmp/gi.txt
for fr in 512 1024 2048; do
  echo "== prt-photons glass_sphere --face-res $fr"
  build-dev/bin/prt-photons data/scenes/glass_sphere.json --backend cuda --face-res $fr --per-pixel 8 --gather-radius 2.5 2>&1 | grep -E "photons in|phases" | tail -3
done
echo "ALL_DONE $(( $(date +%s) - s0 )) s"
