#!/usr/bin/env bash
# Issue 17, after gpu21c.sh on the same warm machine (its 500M room's radii pool in /tmp/w500):
# prt-bricks from points with the new default of one cell worker per thread (16), and prt-radii on
# the 500M room with --memory 12G (bounded memory) against its default (half the RAM).
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"
exec > >(tee -a "$out/log21d.txt") 2>&1
s0=$(date +%s)
deps="-DCMAKE_PREFIX_PATH=$PWD/.device-deps/usr -DPRT_WITH_PCL=OFF -DPRT_WITH_OPENMESH=OFF -DPRT_WITH_OIIO=OFF -DPRT_WITH_PYTHON=OFF -DPRT_WITH_GLFW=OFF -DCMAKE_BUILD_TYPE=Release"
cmake -S . -B build-dev $deps > /tmp/cmake.txt 2>&1 || tail -5 /tmp/cmake.txt
cmake --build build-dev -j16 --target prt-bricks prt-synth prt-radii >/tmp/build.txt 2>&1 || grep -E "error" /tmp/build.txt | head -30
echo "build: $(( $(date +%s) - s0 )) s"
bin=$PWD/build-dev/bin; w=/tmp/w500
t() { date +%s.%N; }
el() { python3 -c "print(round($(t) - $1, 2))"; }
[ -f $w/r.pool ] || { echo "no /tmp/w500/r.pool: run gpu21c.sh first"; exit 1; }
rm -f $w/b.pool
s=$(t); /usr/bin/time -f "bricks max RSS %M KB" $bin/prt-bricks $w/r.pool -o $w/b16.pool --memory 12G --stats-json $out/bricks500_w16.json 2> $w/b16.err; echo "bricks 500M (--memory 12G, default: 16 cell workers): rc $? $(el $s) s"; tail -6 $w/b16.err
rm -f $w/b16.pool
s=$(t); /usr/bin/time -f "radii max RSS %M KB" $bin/prt-radii $w/r.pool -o $w/r12.pool --memory 12G --quiet --stats-json $out/radii500_12G.json; echo "radii 500M --memory 12G: $(el $s) s"
echo "ALL_DONE $(( $(date +%s) - s0 )) s"
