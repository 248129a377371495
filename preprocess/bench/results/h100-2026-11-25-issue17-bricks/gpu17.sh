#!/usr/bin/env bash
# Issue 17 GPU check: CUDA build, ctest -L gpu, prt-bench float octree vs bricks on one pool
# (1M-point sphere, prt-bricks --keep-float), CUDA and CPU renders of both compared.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"
exec > >(tee -a "$out/log17.txt") 2>&1
start=$(date +%s); stamp() { echo "[$(( $(date +%s) - start )) s] $*"; }
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
deps="-DCMAKE_PREFIX_PATH=$PWD/.device-deps/usr -DPRT_WITH_PCL=OFF -DPRT_WITH_OPENMESH=OFF -DPRT_WITH_OIIO=OFF -DPRT_WITH_GLFW=OFF -DCMAKE_BUILD_TYPE=Release"
cmake -S . -B build-dev $deps >"$out/configure.txt" 2>&1 || { tail -30 "$out/configure.txt"; exit 1; }
cmake --build build-dev -j16 >/tmp/build.txt 2>&1 || { grep -E "error" /tmp/build.txt | head -30; }
stamp built
(cd build-dev && ctest -L gpu -j4 --timeout 200 2>&1 | tail -40) | tee "$out/gpu_tests.txt"
stamp tests
bin=$PWD/build-dev/bin
w=/tmp/w17; rm -rf $w; mkdir -p $w
$bin/prt-synth sphere -n 1000000 -o $w/s.pool --quiet && $bin/prt-radii $w/s.pool -o $w/s.pool --quiet \
  && $bin/prt-octree $w/s.pool -o $w/s.pool --quiet && $bin/prt-cull $w/s.pool -o $w/s.pool --quiet \
  && $bin/prt-bricks $w/s.pool -o $w/b.pool --keep-float --quiet || echo "pipeline failed"
for rep in 1 2; do for mode in float bricks; do
  extra=""; [ $mode = bricks ] && extra="--bricks"
  $bin/prt-bench --backend cuda $w/b.pool $extra --frames 50 --warmup 10 --quiet --json /tmp/b.json >/dev/null 2>/tmp/be.txt || { echo "bench $mode failed"; tail -3 /tmp/be.txt; continue; }
  python3 - "$mode" <<'PY' | tee -a "$out/bench17.txt"
import json, sys
j = json.load(open('/tmp/b.json'))
print(sys.argv[1].ljust(7), j['device'], ' '.join('%s %.3f Grays/s' % (x['name'], x['grays_per_s']) for x in j['scenarios']))
PY
done; done
stamp bench
for b in cuda cpu; do
  $bin/prt-play $w/b.pool --backend $b --width 512 --height 512 --out $w/float_$b.pfm --quiet || echo "render float $b failed"
  $bin/prt-play $w/b.pool --bricks --backend $b --width 512 --height 512 --out $w/bricks_$b.pfm --quiet || echo "render bricks $b failed"
done
python3 - $w <<'PY' | tee "$out/compare17.txt"
import sys, numpy as np
def pfm(p):
    with open(p, 'rb') as f:
        kind = f.readline().strip(); w, h = map(int, f.readline().split()); s = float(f.readline())
        c = 3 if kind == b'PF' else 1
        return np.frombuffer(f.read(), dtype='<f4' if s < 0 else '>f4').reshape(h, w, c)
d = sys.argv[1]
def cmp(a, b):
    x, y = pfm(f'{d}/{a}.pfm'), pfm(f'{d}/{b}.pfm'); e = np.abs(x - y)
    mse = float(((x - y) ** 2).mean()); peak = float(max(x.max(), 1e-9))
    psnr = 10 * np.log10(peak ** 2 / mse) if mse > 0 else float('inf')
    print('%-12s vs %-12s max|d| %.3g  mean|d| %.3g  PSNR %.1f dB  pixels differing %d' % (a, b, e.max(), e.mean(), psnr, int((e.max(axis=2) > 1e-6).sum())))
cmp('bricks_cuda', 'bricks_cpu'); cmp('float_cuda', 'float_cpu'); cmp('bricks_cuda', 'float_cuda'); cmp('bricks_cpu', 'float_cpu')
PY
cp $w/*.pfm "$out/" 2>/dev/null
stamp done
