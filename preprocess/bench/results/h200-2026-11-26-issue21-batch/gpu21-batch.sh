#!/bin/bash
# The issue 21 throughput target on the GPU host (16 cores): 200 scans of 100k..1M points through
# prt-import, prt-radii and prt-octree, 16 independent serial pipelines against prt-batch's local
# cluster of 16 workers (scripts/bench-batch.sh), with Debian's Python 3.11 + Dask carried as a
# bundle (make-python-bundle.sh; the host's own Python 3.12 has no Dask).
# Run from the repository root by the device tool, with .device-deps carried (header-only
# dependencies and pybundle.tar.gz); writes under $OUT.
set -uo pipefail
OUT=${OUT:-/tmp/out}
mkdir -p "$OUT"
exec > >(tee "$OUT/log.txt") 2>&1
nproc; lscpu | grep -m1 "Model name"; free -g | head -2; python3 --version; ldd --version | head -1
t0=$(date +%s)
cmake -S . -B build-dev -DCMAKE_PREFIX_PATH=$PWD/.device-deps/usr -DPRT_WITH_PCL=OFF -DPRT_WITH_OPENMESH=OFF \
    -DPRT_WITH_OIIO=OFF -DPRT_WITH_PYTHON=OFF -DPRT_WITH_GLFW=OFF -DCMAKE_BUILD_TYPE=Release >"$OUT/cmake.txt" 2>&1 ||
    { tail -30 "$OUT/cmake.txt"; exit 1; }
cmake --build build-dev -j16 --target prt-import prt-radii prt-octree >"$OUT/build.txt" 2>&1 ||
    { tail -30 "$OUT/build.txt"; exit 1; }
echo "build: $(( $(date +%s) - t0 )) s"
mkdir -p /tmp/pyb && tar -xzf .device-deps/pybundle.tar.gz -C /tmp/pyb
PY=/tmp/pyb/pybundle/bin/python3
$PY -c 'import sys, distributed, psutil, xxhash; print(sys.version.split()[0], "distributed", distributed.__version__)' || exit 1
export PRT_PYTHON=$PY TMPDIR=/tmp
scripts/bench-batch.sh build-dev 200 100000 1000000 16 2>&1 | tee "$OUT/bench-200x16.txt"
