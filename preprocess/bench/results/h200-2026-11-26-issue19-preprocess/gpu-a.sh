#!/bin/bash
# Issue 19, loads round A: one build per variant of load_32_bytes (core/math.h): __ldg pair (A,
# PRT_LOAD_ASM=0) against one volatile asm pair that ptxas cannot split (B, PRT_LOAD_ASM=1);
# prt-bench's 1M room, interleaved rounds; deep blending's cost on A; SASS of the splat kernel.
set -uo pipefail
OUT=${OUT:-/tmp/out}
mkdir -p "$OUT"
exec > >(tee "$OUT/a.txt") 2>&1
nvidia-smi --query-gpu=name,clocks.sm,clocks.max.sm --format=csv,noheader
flags="-DCMAKE_PREFIX_PATH=$PWD/.device-deps/usr -DPRT_WITH_PCL=OFF -DPRT_WITH_OPENMESH=OFF -DPRT_WITH_OIIO=OFF -DPRT_WITH_PYTHON=OFF -DPRT_WITH_GLFW=OFF -DCMAKE_BUILD_TYPE=Release"
sass() {  # the splat-only Z-order megakernel's SASS
    /usr/local/cuda/bin/cuobjdump -sass "$1" | awk '/Function : /{p = /render_kernelILb1ELi4ELj1E/} p' | gzip > "$2"
}
bench() {  # bench NAME BINARY ARGS...
    local name=$1 bin=$2; shift 2
    local t=$SECONDS
    $bin "$@" -q --json $OUT/$name.json >/dev/null 2>&1
    python3 -c "
import json; d = json.load(open('$OUT/$name.json'))
print('$name', [(s.get('name'), round(s['grays_per_s'], 3), round(s.get('leaves_per_ray', 0), 2)) for s in d['scenarios']], '$((SECONDS - t)) s')"
}
t0=$SECONDS
cmake -S . -B build-dev $flags >/tmp/a.cmake.txt 2>&1 &&
    cmake --build build-dev -j16 --target prt-bench >/tmp/a.build.txt 2>&1 || { tail -30 /tmp/a.build.txt; exit 1; }
echo "build A: $((SECONDS - t0)) s"
cp build-dev/bin/prt-bench /tmp/pb-A
sass /tmp/pb-A $OUT/A.sass.gz
S="--scenarios primary,shadow,reflect4,full4 --frames 50"
bench A-r1 /tmp/pb-A $S
bench A-nodeep /tmp/pb-A --scenarios primary,full4 --frames 50 --no-deep-blending
t1=$SECONDS
sed -i 's/^#define PRT_LOAD_ASM 0/#define PRT_LOAD_ASM 1/' runtime/core/include/prt/core/math.h
grep -n "define PRT_LOAD_ASM" runtime/core/include/prt/core/math.h
cmake --build build-dev -j16 --target prt-bench >/tmp/b.build.txt 2>&1 || { grep -E "error" -A3 /tmp/b.build.txt | head -30; exit 1; }
echo "build B: $((SECONDS - t1)) s"
cp build-dev/bin/prt-bench /tmp/pb-B
sass /tmp/pb-B $OUT/B.sass.gz
bench B-r1 /tmp/pb-B $S
bench A-r2 /tmp/pb-A $S
bench B-r2 /tmp/pb-B $S
echo "ALL_DONE $((SECONDS - t0)) s"
