#!/usr/bin/env bash
# Issue 19 on the GPU host (one H200), 2026-12-01: this tree built there with CUDA (sm_90); its GPU
# suites (`ctest -L gpu`), the ISO, real-data, fidelity and batch tests of this reduced build (no
# PCL, OpenMesh, OIIO: those that need them must skip), then the preprocessing chain as a user on
# this machine runs it (BACKEND=auto: prt-radii and prt-cull on the GPU) with this tree's prt-iso
# and with the base's (carried in .ab/base/bin, built on the dev VM), 2 and 16 cores.
# Usage (repository root): bash preprocess/bench/results/h200-2026-12-01-issue19-iso/gpu-i2.sh
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/i2.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; t0=$SECONDS
cmake -S . -B build-gpu -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$PWD/.device-deps/usr -DPRT_WITH_PCL=OFF \
  -DPRT_WITH_OPENMESH=OFF -DPRT_WITH_OIIO=OFF -DPRT_WITH_GLFW=OFF -DPRT_WITH_EMBREE=OFF > $out/configure.log 2>&1 \
  && cmake --build build-gpu -j 16 > $out/build.log 2>&1 || { echo "build failed"; tail -30 $out/build.log; }
echo "build done $((SECONDS - t0)) s"
ctest --test-dir build-gpu -L gpu --output-on-failure --timeout 300 > $out/gpu-tests.log 2>&1
grep -E "tests passed|tests failed|Failed|\(Skipped\)|Not Run" $out/gpu-tests.log | head -30
ctest --test-dir build-gpu -L cpu -R "Iso|RealData|Fidelity|prt_batch" -j 8 --timeout 300 > $out/cpu-tests.log 2>&1
grep -E "tests passed|tests failed|\(Failed\)|\(Skipped\)|Not Run" $out/cpu-tests.log | head -30
echo "tests done $((SECONDS - t0)) s"
mkdir -p /tmp/base/bin; for f in build-gpu/bin/*; do ln -sf "$PWD/$f" /tmp/base/bin/; done
ln -sf "$PWD/.ab/base/bin/prt-iso" /tmp/base/bin/prt-iso
for r in 1 2; do
  echo "== chain, auto, new, round $r"; BACKEND=auto bash scripts/bench-preprocess.sh build-gpu 1000000 2,16 2
  echo "== chain, auto, base prt-iso, round $r"; BACKEND=auto bash scripts/bench-preprocess.sh /tmp/base 1000000 2,16 2
done
echo "ALL_DONE $((SECONDS - t0)) s"
