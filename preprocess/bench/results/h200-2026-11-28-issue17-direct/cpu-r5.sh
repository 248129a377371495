#!/bin/bash
# Issue 17: prt-radii out of core on the GPU host's 16 cores, before and after each tile's Morton
# order, sort and blocks ran in parallel (tiled_knn.cpp order_tile; before: the previous commit's
# tiled_knn.cpp, carried in .device-deps). CPU-only builds of both trees side by side; a 50M-point
# prt-synth room, prt-radii --memory 1G (about 20 tiles), each binary twice, alternating.
set -uo pipefail
OUT=${OUT:-/tmp/out}; mkdir -p "$OUT"; exec > >(tee "$OUT/r5.txt") 2>&1
nproc; grep -m1 "model name" /proc/cpuinfo
F="-DCMAKE_PREFIX_PATH=$PWD/.device-deps/usr -DPRT_WITH_CUDA=OFF -DPRT_WITH_PCL=OFF -DPRT_WITH_OPENMESH=OFF -DPRT_WITH_OIIO=OFF -DPRT_WITH_PYTHON=OFF -DPRT_WITH_GLFW=OFF -DCMAKE_BUILD_TYPE=Release"
t0=$SECONDS
mkdir -p /tmp/old && tar --exclude=./build-dev -cf - . | tar -xf - -C /tmp/old && cp .device-deps/tiled_knn_old.cpp /tmp/old/preprocess/common/tiled_knn.cpp
( cmake -S /tmp/old -B /tmp/bold $F >/tmp/o.cmake.txt 2>&1 && cmake --build /tmp/bold -j8 --target prt-radii prt-synth >/tmp/o.build.txt 2>&1 || { echo "FAIL old"; grep error /tmp/o.build.txt | head; } ) & p1=$!
( cmake -S . -B /tmp/bnew $F >/tmp/n.cmake.txt 2>&1 && cmake --build /tmp/bnew -j8 --target prt-radii prt-synth >/tmp/n.build.txt 2>&1 || { echo "FAIL new"; grep error /tmp/n.build.txt | head; } ) & p2=$!
wait $p1 $p2
echo "built in $((SECONDS - t0)) s"
w=/tmp/r; mkdir -p $w
timeout 120 /tmp/bnew/bin/prt-synth room -n 50000000 -o $w/room.pool --quiet || echo "synth failed"
ls -la $w; echo "synth at $((SECONDS - t0)) s"
for rep in 1 2; do for v in old new; do
  rm -f $w/out.pool
  timeout 150 /tmp/b$v/bin/prt-radii $w/room.pool -o $w/out.pool --memory 1G --spill-folder $w --quiet --stats-json $OUT/radii-$v-r$rep.json || echo "radii $v failed"
  python3 - "$v r$rep" $OUT/radii-$v-r$rep.json <<'PY'
import json, sys
j = json.load(open(sys.argv[2]))
print(sys.argv[1].ljust(8), 'bucket %.2f s, search %.2f s, total %.2f s; tiles %d, halo points %d; radii min %.6g median %.6g mean %.6g max %.6g' % (
    j['index_seconds'], j['search_seconds'], j['total_seconds'], j['tiles'], j['halo_points'], j['min'], j['median'], j['mean'], j['max']))
PY
  echo "at $((SECONDS - t0)) s"
done; done
echo "ALL_DONE $((SECONDS - t0)) s"
