#!/usr/bin/env bash
# The suite's GPU session in one command (the device tool allows few calls), from the repository
# root on the GPU machine (CUDA, CMake, a compiler, Python; the header-only deps in .device-deps):
#   scripts/suite/device.sh OUT_DIR [suite options...]
# Builds the tools, prt-bench and the stability tests (FLANN from .device-deps when lz4 is there,
# for prt-radii), runs the GPU-labelled stability tests, then scripts/suite/run.sh --gpu (1M-point
# models; prt-bench on the CUDA backend) with the given options. Models and build logs stay in
# /tmp/prt-suite-device; OUT_DIR receives at most 8 files: the reports, the GPU test log, the logs.
# PRT_CMAKE_EXTRA adds configure arguments (e.g. -DPRT_LZ4_INCLUDE_DIR=... for FLANN's lz4);
# PRT_DEVICE_BUDGET_S (default 460) bounds the whole script: the suite gets what the build and the
# tests left, so its reports still come back.
set -uo pipefail
out=${1:?usage: device.sh OUT_DIR [suite options...]}
shift
work=/tmp/prt-suite-device
mkdir -p "$out" "$work"
start=$(date +%s)
stamp() { echo "[$(( $(date +%s) - start )) s] $*" | tee -a "$out/device_log.txt"; }
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader | tee "$out/gpu.txt"
stamp configure
cmake -S . -B bd -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$PWD/.device-deps/usr" -DPRT_WITH_PCL=OFF \
    -DPRT_WITH_OPENMESH=OFF -DPRT_WITH_OIIO=OFF -DPRT_WITH_GLFW=OFF -DPRT_WITH_EMBREE=OFF ${PRT_CMAKE_EXTRA:-} >"$work/configure.txt" 2>&1 \
    || { tail -30 "$work/configure.txt"; exit 1; }
grep -E "prt-radii|FLANN" "$work/configure.txt" | tee -a "$out/device_log.txt"
targets="prt-synth prt-octree prt-cull prt-iso prt-mls prt-patches prt-import prt-info prt-accuracy prt-bench prt-play"
targets="$targets prt_stability_gpu_tests"
grep -q "prt-radii.*not built" "$work/configure.txt" || targets="$targets prt-radii"
stamp "build $targets"
cmake --build bd -j16 --target $targets >"$work/build.txt" 2>&1 || { grep -E "error" "$work/build.txt" | head -30; exit 1; }
stamp "gpu stability tests"
(cd bd && timeout 300 ctest -L gpu -R "StabilityGpu|ScaleAndOffsetGpu|PatchExtremesGpu|DegenerateGpu" --output-on-failure --timeout 150) \
    >"$out/gpu_tests.txt" 2>&1
tail -15 "$out/gpu_tests.txt"
stamp "suite"
left=$(( ${PRT_DEVICE_BUDGET_S:-460} - ($(date +%s) - start) ))
timeout $(( left > 30 ? left : 30 )) python3 scripts/suite/suite.py --gpu --bin bd/bin "$@" "$work/suite" 2>&1 | tail -40
for f in results.json results.csv RESULTS.md pareto.png log.txt; do
    [ -f "$work/suite/$f" ] && cp "$work/suite/$f" "$out/$f"
done
stamp done
