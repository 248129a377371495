#!/usr/bin/env bash
# Issue 17, level of detail inside bricks: GPU tests; bricks (LOD prefixes walked, --lod-pixels 0 and 1)
# against the float octree on the 1M sphere and the 1M room; the 100M room built from points and
# streamed under --gpu-budget pool/8 with --lod-pixels 1 (and 0, as before): first image,
# convergence, converged image against in-core, primary rate, 100-frame orbit.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"
exec > >(tee -a "$out/log17j.txt") 2>&1
nvidia-smi --query-gpu=name --format=csv,noheader
deps="-DCMAKE_PREFIX_PATH=$PWD/.device-deps/usr -DPRT_WITH_PCL=OFF -DPRT_WITH_OPENMESH=OFF -DPRT_WITH_OIIO=OFF -DPRT_WITH_GLFW=OFF -DCMAKE_BUILD_TYPE=Release"
t() { date +%s.%N; }
el() { python3 -c "print(round($(t) - $1, 2))"; }
s0=$(t)
cmake -S . -B build-dev $deps >/dev/null 2>&1
cmake --build build-dev -j16 >/tmp/build.txt 2>&1 || { grep -E "error" /tmp/build.txt | head -30; }
echo "build: $(el $s0) s"
(cd build-dev && ctest -L gpu -j4 --timeout 300 > "$out/ctest_gpu.txt" 2>&1; tail -8 "$out/ctest_gpu.txt"; grep -E "Failed|FAILED" "$out/ctest_gpu.txt" | head)
bin=$PWD/build-dev/bin; w=/tmp/w17j; mkdir -p $w
bench() {  # label pool args...
  local label=$1 pool=$2; shift 2
  $bin/prt-bench --backend cuda $pool "$@" --frames 50 --warmup 10 --quiet --json $w/b.json >/dev/null 2>$w/be.txt || { echo "$label failed"; tail -2 $w/be.txt; return; }
  python3 - "$label" $w/b.json <<'PY'
import json, sys
j = json.load(open(sys.argv[2]))
print(sys.argv[1].ljust(24), ' '.join('%s %.3f' % (x['name'], x['grays_per_s']) for x in j['scenarios']))
PY
}
for shape in sphere room; do
  $bin/prt-synth $shape -n 1000000 -o $w/$shape.pool --quiet && $bin/prt-radii $w/$shape.pool -o $w/$shape.pool --quiet \
    && $bin/prt-octree $w/$shape.pool -o $w/$shape.pool --quiet && $bin/prt-cull $w/$shape.pool -o $w/$shape.pool --quiet \
    && $bin/prt-bricks $w/$shape.pool -o $w/${shape}b.pool --keep-float --keep-points 2>&1 | grep -E "LOD|pool"
  cam=""; [ $shape = sphere ] && cam="--eye 0,0,3 --look-at 0,0,0 --up 0,1,0 --fov 45"
  for rep in 1 2; do
    bench "$shape float" $w/${shape}b.pool $cam
    bench "$shape bricks lod0" $w/${shape}b.pool $cam --bricks --lod-pixels 0
    bench "$shape bricks lod1" $w/${shape}b.pool $cam --bricks --lod-pixels 1
  done
done
# ---- 100M room, streamed ----
N=100000000
s0=$(t); $bin/prt-synth room -n $N -o $w/s.pool --quiet; echo "synth $N: $(el $s0) s"
s0=$(t); $bin/prt-radii $w/s.pool -o $w/r.pool --quiet; echo "radii: $(el $s0) s"; rm -f $w/s.pool
s0=$(t); $bin/prt-bricks $w/r.pool -o $w/b.pool --memory 8G --stats-json $w/bricks.json 2>$w/bricks.err; echo "bricks from points: rc $? $(el $s0) s"
rm -f $w/r.pool
grep -v "%" $w/bricks.err | tail -5
pool=$(stat -c %s $w/b.pool); budget=$(( pool / 8 )); echo "pool $pool B, budget $budget B"
cam="--eye 0.55,0.1,0.75 --look-at 0,-0.4,0 --up 0,1,0 --fov 60 --width 1024 --height 1024"
for lod in 1 0; do
  echo "== --lod-pixels $lod"
  s0=$(t); $bin/prt-play $w/b.pool --backend cuda --gpu-budget $budget --lod-pixels $lod $cam --out $w/first$lod.pfm 2>$w/first$lod.err; echo "first image (one pass): $(el $s0) s wall from process start"; grep -E "frame 0" $w/first$lod.err | head -2
  s0=$(t); $bin/prt-play $w/b.pool --backend cuda --gpu-budget $budget --lod-pixels $lod $cam --converge --out $w/conv$lod.pfm 2>$w/conv$lod.err; echo "converged: $(el $s0) s wall"; grep -E "pass|converge" $w/conv$lod.err | tail -2
  $bin/prt-play $w/b.pool --backend cuda --lod-pixels $lod $cam --out $w/incore$lod.pfm --quiet
  $bin/prt-bench --backend cuda $w/b.pool --gpu-budget $budget --lod-pixels $lod $cam --frames 30 --warmup 5 2>&1 | grep -E "streaming|primary" | head -3
  $bin/prt-bench --backend cuda $w/b.pool --lod-pixels $lod $cam --frames 30 --warmup 5 2>&1 | grep -E "primary" | head -2
  $bin/prt-play $w/b.pool --backend cuda --gpu-budget $budget --lod-pixels $lod $cam --frames 100 --orbit 3.6 --converge --out $w/orbitc$lod.pfm 2>$w/orbitc$lod.err
  $bin/prt-play $w/b.pool --backend cuda --lod-pixels $lod $cam --frames 100 --orbit 3.6 --out $w/orbiti$lod.pfm --quiet
done
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
    return int((np.abs(x - y).max(axis=2) > 0).sum()), float(np.abs(x - y).mean())
for lod in '10':
    print('lod %s: converged vs in-core: %d pixels differ (mean abs %.2g)' % ((lod,) + diff('conv' + lod, 'incore' + lod)))
    print('lod %s: orbit last frame converged vs in-core: %d pixels differ (mean abs %.2g)' % ((lod,) + diff('orbitc' + lod, 'orbiti' + lod)))
print('in-core lod 1 vs lod 0: %d pixels differ (mean abs %.3g)' % diff('incore1', 'incore0'))
for lod in '10':
    ms = []; frames = {}
    for line in open(f'{d}/orbitc{lod}.err'):
        m = re.search(r'frame (\d+)( pass \d+)?: ([\d.]+) ms', line)
        if m: ms.append(float(m.group(3))); frames[int(m.group(1))] = frames.get(int(m.group(1)), 0) + float(m.group(3))
    if ms:
        a = np.array(ms); f = np.array(list(frames.values()))
        print('lod %s orbit --converge: %d passes for %d frames: pass median %.2f ms, max %.2f; per frame (all passes) median %.2f, p95 %.2f, max %.2f, frames > 50 ms: %d' % (lod, len(a), len(f), np.median(a), a.max(), np.median(f), np.percentile(f, 95), f.max(), int((f > 50).sum())))
PY
for f in incore1 incore0 conv1; do python3 - $w/$f.pfm $out/$f.png <<'PY' 2>/dev/null
import sys, numpy as np, zlib, struct
p = sys.argv[1]
with open(p, 'rb') as f:
    kind = f.readline().strip(); w, h = map(int, f.readline().split()); s = float(f.readline())
    a = np.frombuffer(f.read(), dtype='<f4' if s < 0 else '>f4').reshape(h, w, 3)[::-1]
a = (np.clip(a, 0, 1) ** (1 / 2.2) * 255 + 0.5).astype(np.uint8)[::2, ::2]
raw = b''.join(b'\x00' + r.tobytes() for r in a)
def chunk(t, d): return struct.pack('>I', len(d)) + t + d + struct.pack('>I', zlib.crc32(t + d) & 0xffffffff)
open(sys.argv[2], 'wb').write(b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', a.shape[1], a.shape[0], 8, 2, 0, 0, 0)) + chunk(b'IDAT', zlib.compress(raw, 6)) + chunk(b'IEND', b''))
PY
done
echo ALL_DONE
