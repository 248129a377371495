#!/usr/bin/env bash
# Issue 17 / 19 on the GPU host (one H200): what today's changes cost on models that fit, and the GPU
# suites. prt-bench of the tree before today (HEAD_BENCH, built from a0ee5da) against today's, in
# alternating rounds, on culled 1M models (prt-synth room and sphere): the float octree (the
# PendingRay footprint is all that changes there), bricks of 32768 splats (the old default) and of
# 8192 (gpu-c1's orbit converges in 88 of 100 frames with them against 46).
# Usage (repository root): BIN=<today's tools> HEAD_BENCH=<old prt-bench> TESTS="<gtest binaries>" bash .../gpu-c2.sh
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/c2.txt") 2>&1
nvidia-smi --query-gpu=name --format=csv,noheader
bin=$(cd "$BIN" && pwd); old=$(cd "$(dirname "$HEAD_BENCH")" && pwd)/$(basename "$HEAD_BENCH")
w=/tmp/w1m; mkdir -p $w; t0=$SECONDS
summ() { python3 - "$1" "$2" <<'PY'
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
echo "pools: $((SECONDS - t0)) s"
for round in 1 2; do
  for shape in room sphere; do
    cam=""; sc="primary,shadow,reflect4,full4"; [ $shape = sphere ] && { cam="--eye 0,0,3 --look-at 0,0,0 --up 0,1,0 --fov 45"; sc="primary,shadow"; }
    for mode in float 32768 8192; do
      extra="--bricks"; pool=$w/$shape-$mode.pool; [ $mode = float ] && { extra=""; pool=$w/$shape-32768.pool; }
      for who in old new; do
        b=$bin/prt-bench; [ $who = old ] && b=$old
        $b --backend cuda $pool $cam $extra --scenarios $sc --frames 30 --warmup 5 --quiet --json $w/b.json >/dev/null 2>$w/be.txt || { echo "$shape $mode $who failed"; tail -2 $w/be.txt; continue; }
        summ "r$round $shape $mode $who" $w/b.json
      done
    done
  done
done
echo "bench: $((SECONDS - t0)) s"
for t in ${TESTS:-}; do
  echo "== $t"; $t --gtest_filter='-*Window*:*Photons*:*LightMap*:*MlsGpu*' 2>&1 | grep -E "^\[  (PASSED|FAILED|SKIPPED) |tests? ran|FAILED  \]" | head -12
done
echo "ALL_DONE $((SECONDS - t0)) s"
