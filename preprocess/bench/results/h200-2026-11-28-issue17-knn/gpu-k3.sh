#!/usr/bin/env bash
# Issue 17, the tree with prt-bricks computing prt-radii's radii itself (a pool without radii): GPU
# tests (the new radii suite, and the suites of the kernels the build and the player run: culling,
# runtime, brick streaming, ISO, stability, patches), the bricks and radii CPU suites, then a 10M
# room two ways (prt-radii -> prt-bricks against prt-bricks straight from prt-synth's pool), brick
# sections compared (../h100-2026-11-25-issue17-outofcore/cmp_sections.py).
# Usage (repository root, carrying .device-deps): bash preprocess/bench/results/.../gpu-k3.sh
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"
exec > >(tee -a "$out/k3.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; git log --oneline -1 2>/dev/null
here=$(cd "$(dirname "$0")" && pwd)
t() { date +%s.%N; }
el() { python3 -c "print(round($(t) - $1, 2))"; }
s0=$(t)
deps="-DCMAKE_PREFIX_PATH=$PWD/.device-deps/usr -DPRT_WITH_PCL=OFF -DPRT_WITH_OPENMESH=OFF -DPRT_WITH_OIIO=OFF -DPRT_WITH_PYTHON=OFF -DPRT_WITH_GLFW=OFF -DCMAKE_BUILD_TYPE=Release"
cmake -S . -B build-dev $deps > /tmp/cmake.txt 2>&1 || tail -5 /tmp/cmake.txt
cmake --build build-dev -j16 --target prt-synth prt-radii prt-bricks prt_radii_gpu_tests prt_cull_gpu_tests prt_runtime_gpu_tests prt_brick_stream_gpu_tests prt_iso_gpu_tests prt_stability_gpu_tests prt_patches_gpu_tests prt_bricks_tests prt_splat_tests > /tmp/build1.txt 2>&1 || grep -E "error" /tmp/build1.txt | head -20
echo "built: $(el $s0) s"
(cd build-dev && ctest -L gpu -E "Window|python|Photons|LightMap|MlsGpu" 2>&1 | grep -vE "^ +Start" > "$out/ctest-gpu.txt"); tail -4 "$out/ctest-gpu.txt"; grep -E "Failed|\*\*\*" "$out/ctest-gpu.txt" | head
(cd build-dev && ctest -R "Bricks|Radii|SplatTools" 2>&1 | tail -3)
bin=$PWD/build-dev/bin; w=/tmp/wk; rm -rf $w; mkdir -p $w
$bin/prt-synth room -n 10000000 -o $w/s.pool --quiet
s=$(t); $bin/prt-radii $w/s.pool -o $w/r.pool --quiet && $bin/prt-bricks $w/r.pool -o $w/a.pool --memory 2G --quiet; echo "10M prt-radii -> prt-bricks: $(el $s) s"
s=$(t); $bin/prt-bricks $w/s.pool -o $w/b.pool --memory 2G 2> $w/b.err; echo "10M prt-bricks from the points without radii: rc $? $(el $s) s"; grep -E "radii|building" $w/b.err | grep -v "%"
python3 $here/../h100-2026-11-25-issue17-outofcore/cmp_sections.py $w/a.pool $w/b.pool 128,129,130,131,132,133,134,135 | tail -1
rm -f $w/*.pool
echo "total $(el $s0) s"
