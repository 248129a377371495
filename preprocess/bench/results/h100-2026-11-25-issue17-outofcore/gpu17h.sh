#!/usr/bin/env bash
# Issue 17 at 500M points. PART=a: build, synth + radii. PART=b: prt-bricks from points --memory 12G.
# PART=c: streaming under --gpu-budget pool/8 (first image, converge, bench, orbit).
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"
exec > >(tee -a "$out/log17h_${PART}.txt") 2>&1
bin=$PWD/build-dev/bin; w=/tmp/w17h; mkdir -p $w
N=${N:-500000000}
t() { date +%s.%N; }
el() { python3 -c "print(round($(t) - $1, 2))"; }
mem() { python3 -c "
import json; j = json.load(open('$1')); print('$2', {k: j[k] for k in j if k in ('peak_rss_bytes','points_per_second','seconds','cells','max_cell_points','pool_bytes_per_point','bricks','build_seconds','total_seconds')})"; }
case $PART in
a)
  deps="-DCMAKE_PREFIX_PATH=$PWD/.device-deps/usr -DPRT_WITH_PCL=OFF -DPRT_WITH_OPENMESH=OFF -DPRT_WITH_OIIO=OFF -DPRT_WITH_GLFW=OFF -DCMAKE_BUILD_TYPE=Release"
  cmake -S . -B build-dev $deps >/dev/null 2>&1
  cmake --build build-dev -j16 >/tmp/build.txt 2>&1 || { grep -E "error" /tmp/build.txt | head -30; }
  rm -rf /tmp/w17g /tmp/w17f; df -h /tmp | tail -1
  s0=$(t); $bin/prt-synth room -n $N -o $w/s.pool --quiet; echo "synth $N: rc $? $(el $s0) s"
  s0=$(t); $bin/prt-radii $w/s.pool -o $w/r.pool --stats-json $w/radii.json 2>$w/radii.err; echo "radii: rc $? $(el $s0) s"; grep -v "%" $w/radii.err | tail -3; rm -f $w/s.pool
  df -h /tmp | tail -1 ;;
b)
  s0=$(t); $bin/prt-bricks $w/r.pool -o $w/b.pool --memory 12G --stats-json $w/bricks.json 2>$w/bricks.err; echo "bricks from points: rc $? $(el $s0) s"
  grep -v "%" $w/bricks.err | tail -7; df -h /tmp | tail -1; cp $w/bricks.json $w/radii.json "$out/" ;;
c)
  pool=$(stat -c %s $w/b.pool); budget=$(( pool / 8 )); echo "pool $pool B, budget $budget B"
  cam="--eye 0.05,-0.2,0.2 --look-at -0.3,-0.6,-0.4 --up 0,1,0 --fov 50 --width 1024 --height 1024"
  s0=$(t); $bin/prt-play $w/b.pool --backend cuda --gpu-budget $budget $cam --out $w/first.pfm 2>$w/first.err; echo "first image (one pass): $(el $s0) s wall from process start"; grep -E "load|frame 0|stream" $w/first.err | head -4
  s0=$(t); $bin/prt-play $w/b.pool --backend cuda --gpu-budget $budget $cam --converge --out $w/conv.pfm 2>$w/conv.err; echo "converged: $(el $s0) s wall"; grep -E "pass|converge" $w/conv.err | tail -3
  $bin/prt-bench --backend cuda $w/b.pool --gpu-budget $budget $cam --frames 30 --warmup 5 2>&1 | grep -vE "%|refining" | tail -4
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
  ;;
esac
