#!/usr/bin/env bash
# Issue 17 on the GPU host (16 cores, one H100): a 500M-point scan-like room end to end (prt-synth,
# prt-radii, prt-bricks from points with --memory 12G and the default cell workers, 8 on 16 threads),
# time and peak memory per step; then the 200M room's bricks with 16 cell workers against 8.
# Usage (repository root, carrying .device-deps): bash preprocess/bench/results/.../gpu21c.sh
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"
exec > >(tee -a "$out/log21c.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; nproc
s0=$(date +%s)
deps="-DCMAKE_PREFIX_PATH=$PWD/.device-deps/usr -DPRT_WITH_PCL=OFF -DPRT_WITH_OPENMESH=OFF -DPRT_WITH_OIIO=OFF -DPRT_WITH_PYTHON=OFF -DPRT_WITH_GLFW=OFF -DCMAKE_BUILD_TYPE=Release"
cmake -S . -B build-dev $deps > /tmp/cmake.txt 2>&1 || tail -5 /tmp/cmake.txt
cmake --build build-dev -j16 --target prt-bricks prt-synth prt-radii >/tmp/build.txt 2>&1 || grep -E "error" /tmp/build.txt | head -30
echo "build: $(( $(date +%s) - s0 )) s"
bin=$PWD/build-dev/bin
rm -rf /tmp/w21 /tmp/w21big/b.pool
t() { date +%s.%N; }
el() { python3 -c "print(round($(t) - $1, 2))"; }
w2=/tmp/w21big
for k in 8 16; do
  [ -f $w2/r.pool ] || break
  s=$(t); $bin/prt-bricks $w2/r.pool -o $w2/b$k.pool --memory 12G --cell-workers $k 2> $w2/b$k.err; echo "== 200M room, --cell-workers $k: rc $? $(el $s) s"; tail -3 $w2/b$k.err | head -2
  rm -f $w2/b$k.pool
done
rm -rf $w2
w=/tmp/w500; rm -rf $w; mkdir -p $w
s=$(t); $bin/prt-synth room -n 500000000 -o $w/s.pool --quiet; echo "synth 500M: $(el $s) s"
s=$(t); /usr/bin/time -f "radii max RSS %M KB" $bin/prt-radii $w/s.pool -o $w/r.pool --quiet --stats-json $out/radii500.json; echo "radii 500M: $(el $s) s"; rm -f $w/s.pool
s=$(t); /usr/bin/time -f "bricks max RSS %M KB" $bin/prt-bricks $w/r.pool -o $w/b.pool --memory 12G --stats-json $out/bricks500.json 2> $w/b.err; echo "bricks 500M (--memory 12G, default workers): rc $? $(el $s) s"; tail -6 $w/b.err
ls -l $w
echo "ALL_DONE $(( $(date +%s) - s0 )) s"
