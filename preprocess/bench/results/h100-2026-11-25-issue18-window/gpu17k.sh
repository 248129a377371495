#!/usr/bin/env bash
# Issue 17/18: all GPU tests (window tests under Xvfb + NVIDIA GLX); streaming upload before (ea0dba7:
# host leaf bounds, one staging buffer) and after (GPU leaf bounds, staging ring) on a 20M room, pool/8.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"
exec > >(tee -a "$out/log17k.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
s0=$(date +%s)
R=/tmp/xroot; mkdir -p $R && tar -C $R -xJf .gl/gl-root.tar.xz
export LD_LIBRARY_PATH=$R/usr/lib/x86_64-linux-gnu${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
base="-DPRT_WITH_PCL=OFF -DPRT_WITH_OPENMESH=OFF -DPRT_WITH_OIIO=OFF -DPRT_WITH_PYTHON=OFF -DCMAKE_BUILD_TYPE=Release"
cmake -S . -B build-dev "-DCMAKE_PREFIX_PATH=$PWD/.device-deps/usr;$R/usr" -DPRT_WITH_GLFW=ON $base > /tmp/cmake.txt 2>&1 || tail -5 /tmp/cmake.txt
cmake --build build-dev -j16 >/tmp/build.txt 2>&1 || { grep -E "error" /tmp/build.txt | head -30; }
echo "builds: $(( $(date +%s) - s0 )) s"
(cd build-dev && ../scripts/gpu-window.sh --root $R -- ctest -L gpu -j4 --timeout 300 --output-on-failure > "$out/ctest_gpu.txt" 2>&1; grep -E "tests passed|\*\*\*|Failed|FAILED" "$out/ctest_gpu.txt" | head -12)
echo "tests: $(( $(date +%s) - s0 )) s"
b=build-dev/bin; w=/tmp/w17k; mkdir -p $w
$b/prt-synth room -n 20000000 -o $w/s.pool --quiet && $b/prt-radii $w/s.pool -o $w/r.pool --quiet && rm $w/s.pool
$b/prt-bricks $w/r.pool -o $w/b.pool --quiet 2>&1 | tail -2
pool=$(stat -c %s $w/b.pool); budget=$(( pool / 8 )); echo "pool $pool B, budget $budget B; data: $(( $(date +%s) - s0 )) s"
cam="--eye 0.55,0.1,0.75 --look-at 0,-0.4,0 --up 0,1,0 --fov 60 --width 1024 --height 1024"
for v in ${VERSIONS:-new}; do
  bin=$b; [ $v = old ] && bin=/tmp/old/b/bin
  echo "== $v converge"
  $bin/prt-play $w/b.pool --backend cuda --gpu-budget $budget $cam --converge --out $w/conv_$v.pfm 2>&1 | grep -E "pass|converge" | head -8
  echo "== $v budget pool/2, no upload limit"
  $bin/prt-play $w/b.pool --backend cuda --gpu-budget $(( pool / 2 )) --upload-per-frame 4G $cam --converge --out $w/big_$v.pfm 2>&1 | grep -E "pass|stream" | head -4
  echo "== $v orbit"
  $bin/prt-play $w/b.pool --backend cuda --gpu-budget $budget $cam --frames 100 --orbit 3.6 --converge --out $w/orbit_$v.pfm 2>$w/orbit_$v.err
  python3 - $w/orbit_$v.err <<'PY'
import re, sys
ms = [float(m.group(1)) for m in re.finditer(r"frame \d+[^:]*: ([\d.]+) ms", open(sys.argv[1]).read())]
gb = [float(m.group(1)) for m in re.finditer(r"([\d.]+) GB/s", open(sys.argv[1]).read())]
ms.sort(); print(f"lines {len(ms)}: median {ms[len(ms)//2]:.1f} ms, p95 {ms[int(len(ms)*0.95)]:.1f}, max {ms[-1]:.1f}; upload GB/s median {sorted(gb)[len(gb)//2] if gb else 0:.2f}")
PY
done
$b/prt-play $w/b.pool --backend cuda $cam --out $w/incore.pfm --quiet && cmp $w/incore.pfm $w/conv_new.pfm && echo "converged image equals the in-core one"
cp $w/orbit_new.err "$out/" 2>/dev/null
echo "ALL_DONE $(( $(date +%s) - s0 )) s"
