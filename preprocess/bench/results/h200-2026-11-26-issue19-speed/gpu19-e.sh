#!/bin/bash
# Issue 19, round E: one build; prt-bench's room with --kernel mega (persistent warps) against
# mega-static, two rounds interleaved; then the GPU tests of the kernels that changed (label gpu).
# (Measured with a prefetching first pass in splat.h, since removed: README.md, row E'.)
set -uo pipefail
OUT=${OUT:-/tmp/out}
mkdir -p "$OUT"
exec > >(tee "$OUT/e.txt") 2>&1
nvidia-smi --query-gpu=name,clocks.sm,clocks.max.sm --format=csv,noheader
flags="-DCMAKE_PREFIX_PATH=$PWD/.device-deps/usr -DPRT_WITH_PCL=OFF -DPRT_WITH_OPENMESH=OFF -DPRT_WITH_OIIO=OFF -DPRT_WITH_PYTHON=OFF -DPRT_WITH_GLFW=OFF -DCMAKE_BUILD_TYPE=Release"
t0=$SECONDS
cmake -S . -B build-dev $flags >/tmp/e.cmake.txt 2>&1 &&
    cmake --build build-dev -j16 --target prt-bench >/tmp/e.build.txt 2>&1 || { tail -30 /tmp/e.build.txt; exit 1; }
echo "build prt-bench: $((SECONDS - t0)) s"
for round in 1 2; do
    for k in mega-static mega; do
        build-dev/bin/prt-bench --kernel $k --scenarios primary,shadow,reflect4,full4 --frames 50 -q \
            --json $OUT/$k-r$round.json >/dev/null 2>&1
        python3 -c "
import json; d = json.load(open('$OUT/$k-r$round.json'))
print('$k round $round', [(s.get('name'), round(s['grays_per_s'], 3), round(s.get('leaves_per_ray', 0), 2)) for s in d['scenarios']])"
    done
done
t1=$SECONDS
cmake --build build-dev -j16 --target prt_runtime_gpu_tests prt_stability_gpu_tests prt_brick_stream_gpu_tests \
    prt_iso_gpu_tests prt_patches_gpu_tests >/tmp/e.build2.txt 2>&1 || { grep -E "error" /tmp/e.build2.txt | head -20; }
echo "build tests: $((SECONDS - t1)) s"
(cd build-dev && ctest -L gpu -E "Window|python|Photons|LightMap|CullGpu|MlsGpu" \
    --timeout 200 --output-on-failure > $OUT/ctest.txt 2>&1; grep -E "tests passed|Failed|FAILED|Not Run|\*\*\*" $OUT/ctest.txt | head -30)
echo "ALL_DONE $((SECONDS - t0)) s"
