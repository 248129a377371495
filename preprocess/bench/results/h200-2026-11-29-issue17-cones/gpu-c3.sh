#!/usr/bin/env bash
# Issue 17 / 19 on the GPU host (16 cores, one H200), the final code of 2026-11-29: (1) the 500M room
# under an eighth of its pool (close view, first image, 100-frame orbit with and without shadow rays,
# prt-bench at the close view) with bricks of 32768 splats (the default until today) and 8192;
# (2) prt-bench of the tree before today against today's on culled 1M models, two alternating rounds;
# (3) the GPU suites. Tools and tests are built on the dev VM and carried (build-cuda/bin, a tarball).
# Usage (repository root): BIN=build-cuda/bin HEAD_BENCH=<old prt-bench> TESTS="<gtest binaries>" bash .../gpu-c3.sh
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/c3.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; nproc
bin=$(cd "$BIN" && pwd); t0=$SECONDS
w=/tmp/w500; mkdir -p $w
s=$SECONDS; $bin/prt-synth room -n 500000000 -o $w/s.pool --quiet; echo "synth 500M: rc $? $((SECONDS - s)) s"
cam="--eye 0.05,-0.2,0.2 --look-at -0.3,-0.6,-0.4 --up 0,1,0 --fov 50 --width 1024 --height 1024"
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
a = sorted(ms); fr = sorted(frames.values())
print('  %d frames, %d converged, %d said not to; %d passes: median %.2f ms, p95 %.2f, max %.2f, passes over 50 ms: %d; per frame median %.2f; unconverged views need %s bricks' % (
    len(frames), len(conv), nc, len(a), a[len(a)//2], a[int(len(a) * 0.95)], a[-1], sum(x > 50 for x in a), fr[len(fr)//2], (min(need), max(need)) if need else '-'))
PY
}
for bs in 32768 8192; do
  s=$SECONDS; /usr/bin/time -f "bricks max RSS %M KB" $bin/prt-bricks $w/s.pool -o $w/b.pool --memory 12G --brick-splats $bs --stats-json $out/bricks-$bs.json 2> $w/bricks.err; echo "== bricks of $bs from points --memory 12G: rc $? $((SECONDS - s)) s"
  grep -v "%" $w/bricks.err | tail -3
  pool=$(stat -c %s $w/b.pool); budget=$(( pool / 8 )); echo "pool $pool B, budget $budget B (pool / 8)"
  s=$(date +%s.%N); $bin/prt-play $w/b.pool --backend cuda --gpu-budget $budget $cam --out $w/first.pfm 2>$w/first.err; echo "first image (one pass): $(python3 -c "print(round($(date +%s.%N) - $s, 2))") s wall from process start"; grep -E "streaming|frame 0" $w/first.err | head -2
  $bin/prt-play $w/b.pool --backend cuda --gpu-budget $budget $cam --converge --out $w/conv.pfm 2>$out/conv-$bs.err; grep -E "pass\(es\)|converge" $out/conv-$bs.err | tail -2
  for variant in "orbit" "orbit-noshadows --no-shadows"; do
    set -- $variant; name=$1; shift
    $bin/prt-play $w/b.pool --backend cuda --gpu-budget $budget $cam --frames 100 --orbit 1.0 --converge "$@" --out $w/$name.pfm 2>$out/$name-$bs.err
    echo "$name $bs $*:"; summ $out/$name-$bs.err
  done
  $bin/prt-bench --backend cuda $w/b.pool --gpu-budget $budget $cam --frames 30 --warmup 5 --scenarios primary,shadow,reflect4 2>&1 | grep -vE "%|refining" | tail -6
done
rm -f $w/s.pool $w/b.pool
echo "500M done: $((SECONDS - t0)) s"
old=$(cd "$(dirname "$HEAD_BENCH")" && pwd)/$(basename "$HEAD_BENCH"); w=/tmp/w1m; mkdir -p $w
sm() { python3 - "$1" "$2" <<'PY'
import json, sys
j = json.load(open(sys.argv[2]))
print(sys.argv[1].ljust(28), ' '.join('%s %.3f' % (x['name'], x['grays_per_s']) for x in j['scenarios']))
PY
}
for shape in room sphere; do
  $bin/prt-synth $shape -n 1000000 -o $w/$shape.pool --quiet && $bin/prt-radii $w/$shape.pool -o $w/$shape.pool --quiet \
    && $bin/prt-octree $w/$shape.pool -o $w/$shape.pool --quiet && $bin/prt-cull $w/$shape.pool -o $w/$shape.pool --quiet || echo "pool $shape failed"
  for bs in 32768 8192; do $bin/prt-bricks $w/$shape.pool -o $w/$shape-$bs.pool --brick-splats $bs --keep-float --quiet || echo "bricks $shape $bs failed"; done
done
for round in 1 2; do
  for shape in room sphere; do
    c=""; sc="primary,shadow,reflect4,full4"; [ $shape = sphere ] && { c="--eye 0,0,3 --look-at 0,0,0 --up 0,1,0 --fov 45"; sc="primary,shadow"; }
    for mode in float 32768 8192; do
      extra="--bricks"; pool=$w/$shape-$mode.pool; [ $mode = float ] && { extra=""; pool=$w/$shape-32768.pool; }
      for who in old new; do
        b=$bin/prt-bench; [ $who = old ] && b=$old
        $b --backend cuda $pool $c $extra --scenarios $sc --frames 30 --warmup 5 --quiet --json $w/b.json >/dev/null 2>$w/be.txt || { echo "$shape $mode $who failed"; tail -2 $w/be.txt; continue; }
        sm "r$round $shape $mode $who" $w/b.json
      done
    done
  done
done
echo "bench done: $((SECONDS - t0)) s"
for t in ${TESTS:-}; do
  echo "== $t"; $t --gtest_filter='-*Window*:*Photons*:*LightMap*:*MlsGpu*' 2>&1 | grep -E "^\[  (PASSED|FAILED|SKIPPED) |FAILED  \]" | head -12
done
echo "ALL_DONE $((SECONDS - t0)) s"
