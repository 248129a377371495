#!/bin/bash
# Issue 19: the landed splat loop (the 81d1185 form, dead shared walk templates removed): bench and GPU tests.
set -uo pipefail
OUT=${OUT:-/tmp/out}; mkdir -p "$OUT"; exec > >(tee "$OUT/r4.txt") 2>&1
nvidia-smi --query-gpu=name,clocks.sm,clocks.max.sm --format=csv,noheader
F="-DCMAKE_PREFIX_PATH=$PWD/.device-deps/usr -DPRT_WITH_PCL=OFF -DPRT_WITH_OPENMESH=OFF -DPRT_WITH_OIIO=OFF -DPRT_WITH_PYTHON=OFF -DPRT_WITH_GLFW=OFF -DCMAKE_BUILD_TYPE=Release"
t0=$SECONDS
cmake -S . -B build-dev $F >/tmp/c.txt 2>&1 && cmake --build build-dev -j16 --target prt-bench >/tmp/b.txt 2>&1 || { echo FAIL; grep error /tmp/b.txt | head; }
echo "built prt-bench in $((SECONDS - t0)) s"
for round in 1 2; do
  build-dev/bin/prt-bench --scenarios primary,shadow,reflect4,full4 --frames 50 -q --json $OUT/bench-final-r$round.json >/dev/null 2>&1
  python3 -c "
import json; d = json.load(open('$OUT/bench-final-r$round.json'))
print('final r$round', [(s.get('name'), round(s['grays_per_s'], 3), round(s.get('leaves_per_ray', 0), 2), round(s.get('splat_tests_per_ray', 0), 2)) for s in d['scenarios']])"
done
t1=$SECONDS
cmake --build build-dev -j16 --target prt_runtime_gpu_tests prt_stability_gpu_tests prt_brick_stream_gpu_tests prt_iso_gpu_tests prt_patches_gpu_tests prt_cull_gpu_tests >/tmp/b2.txt 2>&1 || { grep -E "error" /tmp/b2.txt | head -20; }
echo "built tests in $((SECONDS - t1)) s"
(cd build-dev && ctest -L gpu -E "Window|python|Photons|LightMap|MlsGpu" --timeout 200 --output-on-failure > $OUT/ctest.txt 2>&1; grep -E "tests passed|Failed|FAILED|Not Run|\*\*\*" $OUT/ctest.txt | head -30)
echo "ALL_DONE $((SECONDS - t0)) s"
