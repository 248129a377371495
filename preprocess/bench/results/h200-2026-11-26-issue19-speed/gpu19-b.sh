#!/bin/bash
# Issue 19, round B: the octree walk's descent (octree.h) in three forms, built side by side from
# the working tree with -DPRT_WALK_VARIANT=N, on one host, two rounds interleaved:
#   0: path[] holds node indices; every step reloads the restart node's word (before)
#   1: path[] holds node words: the restart node's word comes from the walk, one dependent global
#      load less per step
#   2: 1, and the current leaf's parent word kept in a register (sibling steps read no path[])
#   3: 1 with PRT_COUNT_WORK=0 (what the work counters cost)
set -uo pipefail
OUT=${OUT:-/tmp/out}
mkdir -p "$OUT"
exec > >(tee "$OUT/b.txt") 2>&1
nvidia-smi --query-gpu=name,clocks.sm,clocks.max.sm --format=csv,noheader
/usr/local/cuda/bin/cuobjdump -sass -fun '_ZN3prt4cuda48_GLOBAL__N__5f8f3c58_15_cuda_backend_cu_7f620a5b13render_kernelILb1ELi4ELj1EEEvNS_4core9SceneViewENS3_13PinholeCameraEjjjjPfPjPy' .device-deps/sass/old81.cubin > $OUT/old81.sass 2>&1
flags="-DCMAKE_PREFIX_PATH=$PWD/.device-deps/usr -DPRT_WITH_PCL=OFF -DPRT_WITH_OPENMESH=OFF -DPRT_WITH_OIIO=OFF -DPRT_WITH_PYTHON=OFF -DPRT_WITH_GLFW=OFF -DCMAKE_BUILD_TYPE=Release"
t0=$SECONDS
build() {  # build DIR DEFINES
    cmake -S . -B $1 $flags -DCMAKE_CXX_FLAGS="$2" -DCMAKE_CUDA_FLAGS="$2" >$1.cmake.txt 2>&1 &&
        cmake --build $1 -j4 --target prt-bench >$1.build.txt 2>&1 || { echo "build $1 failed"; tail -20 $1.build.txt; }
}
# (the first call ran out of time building four at once on a fresh host: a rerun resumes them)
variants=${VARIANTS:-0 1 2 3}
for v in $variants; do
    case $v in 3) d="-DPRT_WALK_VARIANT=1 -DPRT_COUNT_WORK=0" ;; *) d="-DPRT_WALK_VARIANT=$v" ;; esac
    build /tmp/b$v "$d" &
done
wait
echo "builds: $((SECONDS - t0)) s"
for round in 1 2; do
    for v in $variants; do
        /tmp/b$v/bin/prt-bench --scenarios primary,shadow,reflect4 --frames 50 -q --json $OUT/v$v-r$round.json >/dev/null 2>&1
        python3 -c "
import json; d = json.load(open('$OUT/v$v-r$round.json'))
print('variant $v round $round', [(s.get('name'), round(s['grays_per_s'], 3), round(s.get('leaves_per_ray', 0), 2)) for s in d['scenarios']])"
    done
done
