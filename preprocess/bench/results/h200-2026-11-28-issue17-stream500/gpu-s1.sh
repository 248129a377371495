#!/usr/bin/env bash
# Issue 17 on the GPU host (16 cores, one H200): the 500M-point room streamed under --gpu-budget
# pool/8 with today's tree (LOD prefixes inside bricks, which the 2026-11-25 measurement lacked).
# One call: the CPU tools built first, prt-synth + prt-radii (default --memory) running while the
# CUDA tools build; prt-bricks from points (--memory 12G); then the 2026-11-25 close view (first
# image, --converge at --lod-pixels 1 and 2, prt-bench, a converging orbit of 100 frames).
# Usage (repository root, carrying .device-deps): bash preprocess/bench/results/.../gpu-s1.sh
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"
exec > >(tee -a "$out/s1.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; nproc; free -g | head -2; df -h /tmp | tail -1
here=$(cd "$(dirname "$0")" && pwd)
t() { date +%s.%N; }
el() { python3 -c "print(round($(t) - $1, 2))"; }
s0=$(t)
deps="-DCMAKE_PREFIX_PATH=$PWD/.device-deps/usr -DPRT_WITH_PCL=OFF -DPRT_WITH_OPENMESH=OFF -DPRT_WITH_OIIO=OFF -DPRT_WITH_PYTHON=OFF -DPRT_WITH_GLFW=OFF -DCMAKE_BUILD_TYPE=Release"
cmake -S . -B build-dev $deps > /tmp/cmake.txt 2>&1 || tail -5 /tmp/cmake.txt
cmake --build build-dev -j16 --target prt-synth prt-radii > /tmp/build1.txt 2>&1 || grep -E "error" /tmp/build1.txt | head
echo "cpu tools built: $(el $s0) s"
bin=$PWD/build-dev/bin; w=/tmp/w500; rm -rf $w; mkdir -p $w
( s=$(t); $bin/prt-synth room -n 500000000 -o $w/s.pool --quiet; echo "synth 500M: rc $? $(el $s) s"
  s=$(t); /usr/bin/time -f "radii max RSS %M KB" $bin/prt-radii $w/s.pool -o $w/r.pool --quiet --stats-json $out/radii.json; echo "radii: rc $? $(el $s) s (while the CUDA tools build)"; rm -f $w/s.pool ) &
pre=$!
s=$(t); cmake --build build-dev -j16 --target prt-bricks prt-play prt-bench > /tmp/build2.txt 2>&1 || grep -E "error" /tmp/build2.txt | head
echo "cuda tools built: $(el $s) s"
wait $pre
s=$(t); /usr/bin/time -f "bricks max RSS %M KB" $bin/prt-bricks $w/r.pool -o $w/b.pool --memory 12G --stats-json $out/bricks.json 2> $w/bricks.err; echo "bricks from points --memory 12G: rc $? $(el $s) s"
grep -v "%" $w/bricks.err | tail -6; rm -f $w/r.pool
pool=$(stat -c %s $w/b.pool); budget=$(( pool / 8 )); echo "pool $pool B, budget $budget B"
cam="--eye 0.05,-0.2,0.2 --look-at -0.3,-0.6,-0.4 --up 0,1,0 --fov 50 --width 1024 --height 1024"
s=$(t); $bin/prt-play $w/b.pool --backend cuda --gpu-budget $budget $cam --out $w/first.pfm 2>$w/first.err; echo "first image (one pass): $(el $s) s wall from process start"; grep -E "load|streaming|frame 0" $w/first.err | head -4
for lp in 1 2; do
  s=$(t); $bin/prt-play $w/b.pool --backend cuda --gpu-budget $budget $cam --lod-pixels $lp --converge --out $w/conv$lp.pfm 2>$w/conv$lp.err; echo "== --lod-pixels $lp, converge: $(el $s) s wall"; grep -E "pass|converge" $w/conv$lp.err | tail -4
done
$bin/prt-bench --backend cuda $w/b.pool --gpu-budget $budget $cam --frames 30 --warmup 5 2>&1 | grep -vE "%|refining" | tail -6
$bin/prt-play $w/b.pool --backend cuda --gpu-budget $budget $cam --frames 100 --orbit 1.0 --converge --out $w/orbitc.pfm 2>$w/orbitc.err
cp $w/*.err "$out/" 2>/dev/null
python3 - $w <<'PY'
import re, sys, numpy as np
d = sys.argv[1]
ms = []; frames = {}
for line in open(f'{d}/orbitc.err'):
    m = re.search(r'frame (\d+)( pass \d+)?: ([\d.]+) ms', line)
    if m: ms.append(float(m.group(3))); frames[int(m.group(1))] = frames.get(int(m.group(1)), 0) + float(m.group(3))
a = np.array(ms); f = np.array(list(frames.values()))
print('orbit converged: %d passes: median %.2f ms, p95 %.2f, max %.2f, passes > 50 ms: %d; per frame median %.2f max %.2f, frames > 50 ms: %d' % (len(a), np.median(a), np.percentile(a, 95), a.max(), int((a > 50).sum()), np.median(f), f.max(), int((f > 50).sum())))
PY
python3 - $w $out <<'PY'
import sys, numpy as np
def pfm(p):
    with open(p, 'rb') as f:
        f.readline(); w, h = map(int, f.readline().split()); s = float(f.readline())
        return np.fromfile(f, '<f4' if s < 0 else '>f4').reshape(h, w, 3)[::-1]
d, o = sys.argv[1], sys.argv[2]
for n in ('first', 'conv1', 'conv2'):
    try:
        a = np.clip(pfm(f'{d}/{n}.pfm'), 0, 1) ** (1 / 2.2)
        import zlib, struct
        h, w, _ = a.shape; raw = b''.join(b'\0' + (a[y] * 255 + 0.5).astype(np.uint8).tobytes() for y in range(h))
        def chunk(t, b): return struct.pack('>I', len(b)) + t + b + struct.pack('>I', zlib.crc32(t + b) & 0xffffffff)
        open(f'{o}/{n}.png', 'wb').write(b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', w, h, 8, 2, 0, 0, 0)) + chunk(b'IDAT', zlib.compress(raw, 6)) + chunk(b'IEND', b''))
    except Exception as e: print(n, 'no image:', e)
PY
echo "ALL_DONE $(el $s0) s"
