#!/usr/bin/env bash
# Issue 17: the 500M room end to end with two tools: prt-synth (the scan's stand-in for prt-import),
# then prt-bricks straight from its pool (no radii: prt-radii's computed in the process, on the GPU),
# --memory 12G. Runs after gpu-k3.sh on the same (warm) machine: its build-dev.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"
exec > >(tee -a "$out/k4.txt") 2>&1
t() { date +%s.%N; }
el() { python3 -c "print(round($(t) - $1, 2))"; }
s0=$(t)
deps="-DCMAKE_PREFIX_PATH=$PWD/.device-deps/usr -DPRT_WITH_PCL=OFF -DPRT_WITH_OPENMESH=OFF -DPRT_WITH_OIIO=OFF -DPRT_WITH_PYTHON=OFF -DPRT_WITH_GLFW=OFF -DCMAKE_BUILD_TYPE=Release"
[ -x build-dev/bin/prt-bricks ] || { cmake -S . -B build-dev $deps > /tmp/cmake.txt 2>&1; cmake --build build-dev -j16 --target prt-synth prt-bricks > /tmp/build1.txt 2>&1; echo "built (cold machine): $(el $s0) s"; }
bin=$PWD/build-dev/bin; w=/tmp/wk; rm -rf $w; mkdir -p $w
s=$(t); $bin/prt-synth room -n 500000000 -o $w/s.pool --quiet; echo "synth 500M: rc $? $(el $s) s"
s=$(t); /usr/bin/time -f "bricks max RSS %M KB" $bin/prt-bricks $w/s.pool -o $w/b.pool --memory 12G --stats-json $out/bricks500-noradii.json 2> $w/bricks.err; echo "prt-bricks from the points (no radii) --memory 12G: rc $? $(el $s) s"
grep -v "%" $w/bricks.err | tail -7
echo "total $(el $s0) s"
