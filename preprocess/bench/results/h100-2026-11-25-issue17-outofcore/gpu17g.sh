#!/usr/bin/env bash
# Issue 17 at scale: a 100M-point room built straight from points (prt-bricks --memory 8G), then
# streamed under --gpu-budget pool/8: first image, convergence, primary rate, 100-frame orbit.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"
exec > >(tee -a "$out/log17g.txt") 2>&1
nvidia-smi --query-gpu=name --format=csv,noheader
deps="-DCMAKE_PREFIX_PATH=$PWD/.device-deps/usr -DPRT_WITH_PCL=OFF -DPRT_WITH_OPENMESH=OFF -DPRT_WITH_OIIO=OFF -DPRT_WITH_GLFW=OFF -DCMAKE_BUILD_TYPE=Release"
cmake -S . -B build-dev $deps >/dev/null 2>&1
cmake --build build-dev -j16 >/tmp/build.txt 2>&1 || { grep -E "error" /tmp/build.txt | head -30; }
bin=$PWD/build-dev/bin; w=/tmp/w17g; mkdir -p $w; rm -f $w/*.err
N=${N:-100000000}
t() { date +%s.%N; }
el() { python3 -c "print(round($(t) - $1, 2))"; }
if [ ! -f $w/r.pool ]; then
  s0=$(t); $bin/prt-synth room -n $N -o $w/s.pool --quiet; echo "synth $N: $(el $s0) s"
  s0=$(t); $bin/prt-radii $w/s.pool -o $w/r.pool --quiet --stats-json $w/radii.json; echo "radii: $(el $s0) s"; rm -f $w/s.pool
fi
s0=$(t); $bin/prt-bricks $w/r.pool -o $w/b.pool --memory 8G --stats-json $w/bricks.json 2>$w/bricks.err; echo "bricks from points: rc $? $(el $s0) s"
grep -v "%" $w/bricks.err | tail -6
df -h /tmp | tail -1
pool=$(stat -c %s $w/b.pool); budget=$(( pool / 8 )); echo "pool $pool B, budget $budget B"
cam="--eye 0.55,0.1,0.75 --look-at 0,-0.4,0 --up 0,1,0 --fov 60 --width 1024 --height 1024"
s0=$(t); $bin/prt-play $w/b.pool --backend cuda --gpu-budget $budget $cam --out $w/first.pfm 2>$w/first.err; echo "first image (one pass): $(el $s0) s wall from process start"; grep -E "load|frame 0|stream" $w/first.err | head -4
s0=$(t); $bin/prt-play $w/b.pool --backend cuda --gpu-budget $budget $cam --converge --out $w/conv.pfm 2>$w/conv.err; echo "converged: $(el $s0) s wall"; grep -E "pass|converge" $w/conv.err | tail -3
$bin/prt-play $w/b.pool --backend cuda $cam --out $w/incore.pfm --quiet
$bin/prt-bench --backend cuda $w/b.pool --gpu-budget $budget $cam --frames 30 --warmup 5 2>&1 | grep -E "streaming|primary|cuda on" | head -5
$bin/prt-bench --backend cuda $w/b.pool $cam --frames 30 --warmup 5 2>&1 | grep -E "primary|cuda on" | head -3
$bin/prt-play $w/b.pool --backend cuda --gpu-budget $budget $cam --frames 100 --orbit 3.6 --converge --out $w/orbitc.pfm 2>$w/orbitc.err
$bin/prt-play $w/b.pool --backend cuda --gpu-budget $budget $cam --frames 100 --orbit 3.6 --out $w/orbit.pfm 2>$w/orbit.err
$bin/prt-play $w/b.pool --backend cuda $cam --frames 100 --orbit 3.6 --out $w/orbit_incore.pfm --quiet
cp $w/*.err $w/*.json "$out/" 2>/dev/null
python3 - $w <<'PY'
import re, sys, numpy as np
d = sys.argv[1]
def pfm(p):
    with open(p, 'rb') as f:
        kind = f.readline().strip(); w, h = map(int, f.readline().split()); s = float(f.readline())
        c = 3 if kind == b'PF' else 1
        return np.frombuffer(f.read(), dtype='<f4' if s < 0 else '>f4').reshape(h, w, c)
def diff(a, b):
    x, y = pfm(f'{d}/{a}.pfm'), pfm(f'{d}/{b}.pfm')
    return int((np.abs(x - y).max(axis=2) > 0).sum())
print('converged vs in-core: %d pixels differ' % diff('conv', 'incore'))
print('orbit converged last frame vs in-core: %d pixels differ' % diff('orbitc', 'orbit_incore'))
for name in ['orbit', 'orbitc']:
    ms = []; frames = {}
    for line in open(f'{d}/{name}.err'):
        m = re.search(r'frame (\d+)( pass \d+)?: ([\d.]+) ms', line)
        if m: ms.append(float(m.group(3))); frames[int(m.group(1))] = frames.get(int(m.group(1)), 0) + float(m.group(3))
    if ms:
        a = np.array(ms); f = np.array(list(frames.values()))
        print('%-7s %d passes: median %.2f ms, p95 %.2f, max %.2f, > 50 ms: %d; per frame (all passes) median %.2f max %.2f' % (name, len(a), np.median(a), np.percentile(a, 95), a.max(), int((a > 50).sum()), np.median(f), f.max()))
PY
