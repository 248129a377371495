#!/usr/bin/env bash
# Issue 21 / 17 on the GPU host (16 cores, one H100): (1) GPU culling against the CPU after the leaf
# hash change (CullGpu, label gpu) and the bricks-from-points tests; (2) prt-bricks from points on a
# 50M-point room with --cell-workers 1, 2, 4, 8 (cells built at once in one process, 16 threads
# shared), each compared with workers 1 section by section; (3) a 200M-point room end to end (synth,
# radii, bricks with the default 4 cell workers, --memory 12G).
# Usage (repository root, carrying .device-deps): bash preprocess/bench/results/.../gpu21b.sh
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"
exec > >(tee -a "$out/log21b.txt") 2>&1
here=$(cd "$(dirname "$0")" && pwd)
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; nproc
s0=$(date +%s)
deps="-DCMAKE_PREFIX_PATH=$PWD/.device-deps/usr -DPRT_WITH_PCL=OFF -DPRT_WITH_OPENMESH=OFF -DPRT_WITH_OIIO=OFF -DPRT_WITH_PYTHON=OFF -DPRT_WITH_GLFW=OFF -DCMAKE_BUILD_TYPE=Release"
cmake -S . -B build-dev $deps > /tmp/cmake.txt 2>&1 || tail -5 /tmp/cmake.txt
cmake --build build-dev -j16 --target prt_cull_gpu_tests prt_bricks_tests prt-bricks prt-synth prt-radii >/tmp/build.txt 2>&1 || grep -E "error" /tmp/build.txt | head -30
echo "build: $(( $(date +%s) - s0 )) s"
(cd build-dev && ctest -R "CullGpu|BricksFromPoints" -j4 --timeout 300 --output-on-failure > "$out/ctest21b.txt" 2>&1; grep -E "tests passed|\*\*\*|Failed|Not Run" "$out/ctest21b.txt" | head -20)
bin=$PWD/build-dev/bin; w=/tmp/w21; mkdir -p $w
t() { date +%s.%N; }
el() { python3 -c "print(round($(t) - $1, 2))"; }
if [ ! -f $w/r.pool ]; then
  s=$(t); $bin/prt-synth room -n 50000000 -o $w/s.pool --quiet; echo "synth 50M: $(el $s) s"
  s=$(t); $bin/prt-radii $w/s.pool -o $w/r.pool --quiet; echo "radii: $(el $s) s"; rm -f $w/s.pool
fi
for k in 1 2 4 8; do
  s=$(t); $bin/prt-bricks $w/r.pool -o $w/k$k.pool --memory 2G --cell-workers $k --stats-json $out/k$k.json 2> $w/k$k.err
  echo "== 50M room, --memory 2G, --cell-workers $k: rc $? $(el $s) s"; grep -E "cells \(|partitioning|building" $w/k$k.err
  [ $k = 1 ] || python3 $here/../h100-2026-11-25-issue17-outofcore/cmp_sections.py $w/k1.pool $w/k$k.pool 128,129,130,131,132,133,134,135 | tail -1
  rm -f $w/k$k.pool.tmp*
done
rm -f $w/k2.pool $w/k4.pool $w/k8.pool
w2=/tmp/w21big; rm -rf $w2; mkdir -p $w2
s=$(t); $bin/prt-synth room -n 200000000 -o $w2/s.pool --quiet; echo "synth 200M: $(el $s) s"
s=$(t); /usr/bin/time -f "radii max RSS %M KB" $bin/prt-radii $w2/s.pool -o $w2/r.pool --quiet; echo "radii 200M: $(el $s) s"; rm -f $w2/s.pool
s=$(t); /usr/bin/time -f "bricks max RSS %M KB" $bin/prt-bricks $w2/r.pool -o $w2/b.pool --memory 12G --stats-json $out/big.json 2> $w2/b.err; echo "bricks 200M (--memory 12G, default workers): rc $? $(el $s) s"; tail -6 $w2/b.err
ls -l $w2
echo "ALL_DONE $(( $(date +%s) - s0 )) s"
