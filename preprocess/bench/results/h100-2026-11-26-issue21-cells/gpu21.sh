#!/usr/bin/env bash
# Issue 21 on the GPU host (16 cores, one H100): (1) culling on the GPU still keeps what the CPU keeps
# now that a leaf's probes hash its cell (CullGpu, BricksFromPoints: label gpu and cpu); (2) a
# scan-like room's bricks built from points in one process (16 threads) against the staged build
# (prt-bricks --stage plan, then the cells as P concurrent processes of 16 / P threads, started by
# xargs: this host has no Dask, so xargs stands in for the workers; then --stage merge): time of each
# stage, and the brick sections compared; (3) what Python this host has, for Dask.
# Usage (repository root, carrying .device-deps): bash preprocess/bench/results/.../gpu21.sh
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"
exec > >(tee -a "$out/log21.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; nproc
s0=$(date +%s)
deps="-DCMAKE_PREFIX_PATH=$PWD/.device-deps/usr -DPRT_WITH_PCL=OFF -DPRT_WITH_OPENMESH=OFF -DPRT_WITH_OIIO=OFF -DPRT_WITH_PYTHON=OFF -DPRT_WITH_GLFW=OFF -DCMAKE_BUILD_TYPE=Release"
cmake -S . -B build-dev $deps > /tmp/cmake.txt 2>&1 || tail -5 /tmp/cmake.txt
cmake --build build-dev -j16 --target prt_cull_tests prt_bricks_tests prt-bricks prt-synth prt-radii >/tmp/build.txt 2>&1 || grep -E "error" /tmp/build.txt | head -30
echo "build: $(( $(date +%s) - s0 )) s"
(cd build-dev && ctest -R "Cull|BricksFromPoints" -j4 --timeout 300 --output-on-failure > "$out/ctest21.txt" 2>&1; grep -E "tests passed|\*\*\*|Failed|Not Run" "$out/ctest21.txt" | head -20)
python3 -c "import sys; print('python', sys.version.split()[0])"
python3 -c "import dask, distributed; print('dask', dask.__version__)" 2>&1 | tail -1
python3 -c "import psutil, tornado, msgpack, cloudpickle; print('dask deps present')" 2>&1 | tail -1
bin=$PWD/build-dev/bin; w=/tmp/w21; rm -rf $w; mkdir -p $w
N=${N:-50000000}; P=${P:-4}; MEM=${MEM:-2G}
t() { date +%s.%N; }
el() { python3 -c "print(round($(t) - $1, 2))"; }
s=$(t); $bin/prt-synth room -n $N -o $w/s.pool --quiet; echo "synth $N: $(el $s) s"
s=$(t); $bin/prt-radii $w/s.pool -o $w/r.pool --quiet; echo "radii: $(el $s) s"; rm -f $w/s.pool
s=$(t); $bin/prt-bricks $w/r.pool -o $w/one.pool --memory $MEM --stats-json $out/one.json 2> $w/one.err; echo "one process, 16 threads, --memory $MEM: rc $? $(el $s) s"; tail -4 $w/one.err
mkdir -p $w/cells
s=$(t); $bin/prt-bricks $w/r.pool -o $w/staged.pool --memory $MEM --stage plan --cells-folder $w/cells --stats-json $out/plan.json --quiet; echo "plan: rc $? $(el $s) s"
cells=$(python3 -c "import json; print(json.load(open('$out/plan.json'))['cells'])"); echo "cells: $cells"
s=$(t); seq 0 $((cells - 1)) | xargs -P $P -I{} sh -c "$bin/prt-bricks $w/r.pool -o $w/staged.pool --memory $MEM --stage cells --cells {}:\$(({} + 1)) --cells-folder $w/cells -j $((16 / P)) --quiet || echo FAILED {}"; echo "cells, $P processes x $((16 / P)) threads: $(el $s) s"
s=$(t); $bin/prt-bricks $w/r.pool -o $w/staged.pool --memory $MEM --stage merge --cells-folder $w/cells --stats-json $out/merge.json 2> $w/merge.err; echo "merge: rc $? $(el $s) s"; tail -3 $w/merge.err
python3 $(dirname "$0")/../h100-2026-11-25-issue17-outofcore/cmp_sections.py $w/one.pool $w/staged.pool 128,129,130,131,132,133,134,135
echo "ALL_DONE $(( $(date +%s) - s0 )) s"
