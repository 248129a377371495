#!/usr/bin/env bash
# Issue 17: prt-radii's GPU k-NN (runtime/cuda/src/knn.cu), its warp-coherent walk, on the GPU host
# (16 cores, one H200); then the 500M room end to end: prt-synth, prt-radii (CUDA, --memory 12G),
# prt-bricks from points (--memory 12G).
# Builds the radii tool and its tests, runs the GPU agreement tests, then prt-synth rooms of 1M, 10M
# and 100M points through prt-radii with --backend cpu and --backend cuda: time, peak RSS, and the
# radii sections' checksums compared (../h100-2026-11-25-issue17-outofcore/cmp_sections.py, type 6).
# Usage (repository root, carrying .device-deps): bash preprocess/bench/results/.../gpu-k1.sh
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"
exec > >(tee -a "$out/k2.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; nproc; free -g | head -2
here=$(cd "$(dirname "$0")" && pwd)
t() { date +%s.%N; }
el() { python3 -c "print(round($(t) - $1, 2))"; }
s0=$(t)
deps="-DCMAKE_PREFIX_PATH=$PWD/.device-deps/usr -DPRT_WITH_PCL=OFF -DPRT_WITH_OPENMESH=OFF -DPRT_WITH_OIIO=OFF -DPRT_WITH_PYTHON=OFF -DPRT_WITH_GLFW=OFF -DCMAKE_BUILD_TYPE=Release"
cmake -S . -B build-dev $deps > /tmp/cmake.txt 2>&1 || tail -5 /tmp/cmake.txt
cmake --build build-dev -j16 --target prt-synth prt-radii prt-bricks prt_radii_gpu_tests prt_splat_tests > /tmp/build1.txt 2>&1 || grep -E "error" /tmp/build1.txt | head -20
echo "built: $(el $s0) s"
bin=$PWD/build-dev/bin
s=$(t); build-dev/tests/preprocess/splat/prt_radii_gpu_tests > "$out/radii-gpu-tests.txt" 2>&1; echo "prt_radii_gpu_tests rc $? $(el $s) s"; grep -E "OK|FAILED|PASSED|SKIPPED|Failure|first at" "$out/radii-gpu-tests.txt" | head -20
build-dev/tests/preprocess/splat/prt_splat_tests --gtest_filter='*Radii*:*Backend*' 2>&1 | grep -E "OK \]|FAILED|PASSED" | tail -20
w=/tmp/wk; rm -rf $w; mkdir -p $w
for n in 1000000 10000000 100000000; do
  $bin/prt-synth room -n $n -o $w/s.pool --quiet
  for b in cuda cpu; do
    s=$(t); /usr/bin/time -f "max RSS %M KB" $bin/prt-radii $w/s.pool -o $w/r-$b.pool --backend $b --quiet --stats-json $w/$b.json 2> $w/$b.err
    echo "room $n --backend $b: rc $? wall $(el $s) s; $(tail -1 $w/$b.err)"
    python3 -c "import json; d=json.load(open('$w/$b.json')); print('  index %.3f s, search %.3f s, radii %.3f s, total %.3f s, clamped %d, median %.9g, mean %.12g' % (d['index_seconds'], d['search_seconds'], d['radii_seconds'], d['total_seconds'], d['clamped'], d['median'], d['mean']))"
  done
  python3 $here/../h100-2026-11-25-issue17-outofcore/cmp_sections.py $w/r-cpu.pool $w/r-cuda.pool 6 | tail -1
  rm -f $w/*.pool
done
s=$(t); $bin/prt-synth room -n 500000000 -o $w/s.pool --quiet; echo "synth 500M: rc $? $(el $s) s"
s=$(t); /usr/bin/time -f "max RSS %M KB" $bin/prt-radii $w/s.pool -o $w/r.pool --memory 12G --quiet --stats-json $w/r500.json 2> $w/r500.err; echo "radii 500M cuda --memory 12G: rc $? $(el $s) s; $(tail -1 $w/r500.err)"
python3 -c "import json; d=json.load(open('$w/r500.json')); print('  backend %s, index %.3f s, search %.3f s, radii %.3f s, total %.3f s, clamped %d, peak_rss %.2f GiB, before write %.2f GiB' % (d['backend'], d['index_seconds'], d['search_seconds'], d['radii_seconds'], d['total_seconds'], d['clamped'], d['peak_rss']/2**30, d['peak_rss_before_write']/2**30))"
rm -f $w/s.pool
s=$(t); /usr/bin/time -f "bricks max RSS %M KB" $bin/prt-bricks $w/r.pool -o $w/b.pool --memory 12G --stats-json $out/bricks500.json 2> $w/bricks.err; echo "bricks from points --memory 12G: rc $? $(el $s) s"
grep -v "%" $w/bricks.err | tail -5
echo "total $(el $s0) s"
