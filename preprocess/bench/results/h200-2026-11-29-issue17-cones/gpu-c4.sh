#!/usr/bin/env bash
# Issue 17 / 19 on the GPU host (one H200): gpu-c3.sh's 1M comparison again (three alternating rounds)
# after two cheaper checks in the bricked walk: the streaming flags are tested only when the view has
# them (bricks.h), and camera rays skip the eye distance (render.h lod_cone).
# Usage (repository root): BIN=build-cuda/bin HEAD_BENCH=<old prt-bench> bash .../gpu-c4.sh
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/c4.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
bin=$(cd "$BIN" && pwd); t0=$SECONDS
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
for round in 1 2 3; do
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
echo "ALL_DONE $((SECONDS - t0)) s"
