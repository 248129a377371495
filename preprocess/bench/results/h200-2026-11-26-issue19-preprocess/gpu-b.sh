#!/bin/bash
# Issue 19, round B: one build (the tools and the GPU tests of the kernels that changed: the
# megakernel's cached occupancy, wave_primary's pixel through item_pixel); prt-bench's room (mega);
# the GPU tests; then scripts/bench-preprocess.sh on 1, 2 and 16 cores (CPU only).
set -uo pipefail
OUT=${OUT:-/tmp/out}
mkdir -p "$OUT"
exec > >(tee "$OUT/b.txt") 2>&1
nvidia-smi --query-gpu=name,clocks.sm,clocks.max.sm --format=csv,noheader
flags="-DCMAKE_PREFIX_PATH=$PWD/.device-deps/usr -DPRT_WITH_PCL=OFF -DPRT_WITH_OPENMESH=OFF -DPRT_WITH_OIIO=OFF -DPRT_WITH_PYTHON=OFF -DPRT_WITH_GLFW=OFF -DCMAKE_BUILD_TYPE=Release"
t0=$SECONDS
cmake -S . -B build-dev $flags >/tmp/b.cmake.txt 2>&1 &&
    cmake --build build-dev -j16 --target prt-bench prt-import prt-radii prt-octree prt-cull prt-iso \
        prt_runtime_gpu_tests prt_stability_gpu_tests prt_brick_stream_gpu_tests prt_iso_gpu_tests \
        prt_patches_gpu_tests >/tmp/b.build.txt 2>&1 || { grep -E "error" -A3 /tmp/b.build.txt | head -30; exit 1; }
echo "build: $((SECONDS - t0)) s"
build-dev/bin/prt-bench --scenarios primary,shadow,reflect4,full4 --frames 50 -q --json $OUT/mega.json >/dev/null 2>&1
python3 -c "
import json; d = json.load(open('$OUT/mega.json'))
print('mega', [(s.get('name'), round(s['grays_per_s'], 3)) for s in d['scenarios']])"
t1=$SECONDS
(cd build-dev && ctest -L gpu -E "Window|python|Photons|LightMap|CullGpu|MlsGpu" \
    --timeout 200 --output-on-failure > $OUT/ctest.txt 2>&1; grep -E "tests passed|Failed|FAILED|Not Run|\*\*\*" $OUT/ctest.txt | head -30)
echo "ctest: $((SECONDS - t1)) s"
t2=$SECONDS
bash scripts/bench-preprocess.sh build-dev 1000000 1,2,16 1 | tee $OUT/preprocess.txt
echo "bench-preprocess: $((SECONDS - t2)) s"
echo "ALL_DONE $((SECONDS - t0)) s"
