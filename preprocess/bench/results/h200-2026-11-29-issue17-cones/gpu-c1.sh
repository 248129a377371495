#!/usr/bin/env bash
# Issue 17 on the GPU host (16 cores, one H200): the 500M room's close view and 100-frame orbit
# under an eighth of its pool, after two changes to streaming: rays leaving a hit keep their camera
# ray's footprint (render.h lod_width_at / lod_cone), and a ray requests only the first missing brick
# on its way and keeps (flags used) no brick past it nor any it walks only through the prefix
# (bricks.h stopped_at_disc, descend_bricked). The same pool, view and orbit as
# h200-2026-11-28-issue17-stream500/gpu-s2.sh (prt-synth room 500M, prt-bricks from points, bricks of
# 32768 splats), then the orbit without shadow rays, and prt-bench at the close view.
# Usage (repository root; BIN: a folder of prebuilt tools, carried, else they are built here from .device-deps):
#   BIN=<folder with prt-synth prt-bricks prt-play prt-bench> bash .../gpu-c1.sh
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"
exec > >(tee -a "$out/c1.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; nproc
t() { date +%s.%N; }
el() { python3 -c "print(round($(t) - $1, 2))"; }
s0=$(t)
bin=${BIN:-}
if [ -z "$bin" ] || ! "$bin/prt-play" --version >/dev/null 2>&1; then
  deps="-DCMAKE_PREFIX_PATH=$PWD/.device-deps/usr -DPRT_WITH_PCL=OFF -DPRT_WITH_OPENMESH=OFF -DPRT_WITH_OIIO=OFF -DPRT_WITH_PYTHON=OFF -DPRT_WITH_GLFW=OFF -DCMAKE_BUILD_TYPE=Release"
  cmake -S . -B build-dev $deps > /tmp/cmake.txt 2>&1 || tail -5 /tmp/cmake.txt
  cmake --build build-dev -j16 --target prt-synth prt-bricks prt-play prt-bench > /tmp/build.txt 2>&1 || grep -E "error" /tmp/build.txt | head
  bin=$PWD/build-dev/bin; echo "tools built: $(el $s0) s"
else
  bin=$(cd "$bin" && pwd); echo "tools carried: $bin"
fi
w=/tmp/w500; mkdir -p $w
if [ ! -s $w/b.pool ]; then
  s=$(t); $bin/prt-synth room -n 500000000 -o $w/s.pool --quiet; echo "synth 500M: rc $? $(el $s) s"
  s=$(t); /usr/bin/time -f "bricks max RSS %M KB" $bin/prt-bricks $w/s.pool -o $w/b.pool --memory 12G --stats-json $out/bricks.json 2> $w/bricks.err; echo "bricks from points --memory 12G: rc $? $(el $s) s"
  grep -v "%" $w/bricks.err | tail -4
fi
pool=$(stat -c %s $w/b.pool); budget=$(( pool / ${DIV:-8} )); echo "pool $pool B, budget $budget B (pool / ${DIV:-8})"
cam="--eye 0.05,-0.2,0.2 --look-at -0.3,-0.6,-0.4 --up 0,1,0 --fov 50 --width 1024 --height 1024"
s=$(t); $bin/prt-play $w/b.pool --backend cuda --gpu-budget $budget $cam --out $w/first.pfm 2>$w/first.err; echo "first image (one pass): $(el $s) s wall from process start"; grep -E "load|frame 0" $w/first.err | head -3
s=$(t); $bin/prt-play $w/b.pool --backend cuda --gpu-budget $budget $cam --converge --out $w/conv.pfm 2>$w/conv.err; echo "== close view, converge: $(el $s) s wall"; grep -E "pass|converge" $w/conv.err | tail -3
summ() { python3 - "$1" <<'PY'
import re, sys
ms = []; frames = {}; conv = set(); nc = 0; need = []
for line in open(sys.argv[1]):
    m = re.search(r'frame (\d+)( pass \d+)?: ([\d.]+) ms.*?(\d+) rays fell back', line)
    if m:
        f = int(m.group(1)); ms.append(float(m.group(3))); frames[f] = frames.get(f, 0) + float(m.group(3))
        if m.group(4) == '0': conv.add(f)
    m = re.search(r'holds (\d+) of the (\d+) bricks', line)
    if m: nc += 1; need.append(int(m.group(2)))
ms.sort(); fr = sorted(frames.values())
print('  %d frames, %d converged, %d said not to; passes %d: median %.2f ms, max %.2f, > 50 ms: %d; per frame max %.2f; unconverged views need %s bricks' % (
    len(frames), len(conv), nc, len(ms), ms[len(ms)//2], ms[-1], sum(x > 50 for x in ms), fr[-1], (min(need), max(need)) if need else '-'))
PY
}
for variant in "orbit" "orbit-noshadows --no-shadows"; do
  set -- $variant; name=$1; shift
  $bin/prt-play $w/b.pool --backend cuda --gpu-budget $budget $cam --frames 100 --orbit 1.0 --converge "$@" --out $w/$name.pfm 2>$w/$name.err
  echo "== $name $*:"; summ $w/$name.err; cp $w/$name.err "$out/"
done
$bin/prt-bench --backend cuda $w/b.pool --gpu-budget $budget $cam --frames 30 --warmup 5 --scenarios primary,shadow,reflect4 2>&1 | grep -vE "%|refining" | tail -7
cp $w/conv.err $w/first.err "$out/" 2>/dev/null
echo "ALL_DONE $(el $s0) s"
