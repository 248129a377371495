#!/bin/bash
# Issue 17: do bricks of 32768 splats (gpu-s2.sh: the 500M room's close view converges under pool/8)
# cost tracing speed on models that fit? Culled 1M room and sphere cut at 131072 (the default) and
# 32768 splats per brick, prt-bench against the float octree, one round (the device budget's rest).
set -uo pipefail
OUT=${OUT:-/tmp/out}; mkdir -p "$OUT"; exec > >(tee "$OUT/s3.txt") 2>&1
nvidia-smi --query-gpu=name --format=csv,noheader
F="-DCMAKE_PREFIX_PATH=$PWD/.device-deps/usr -DPRT_WITH_PCL=OFF -DPRT_WITH_OPENMESH=OFF -DPRT_WITH_OIIO=OFF -DPRT_WITH_PYTHON=OFF -DPRT_WITH_GLFW=OFF -DCMAKE_BUILD_TYPE=Release"
t0=$SECONDS
cmake -S . -B build-dev $F >/tmp/c.txt 2>&1 && cmake --build build-dev -j16 --target prt-bench prt-synth prt-radii prt-octree prt-cull prt-bricks >/tmp/b.txt 2>&1 || { echo "BUILD FAIL"; grep error /tmp/b.txt | head; }
echo "built in $((SECONDS - t0)) s"
w=/tmp/w; mkdir -p $w; bin=build-dev/bin
summ() { python3 - "$1" "$2" <<'PY'
import json, sys
j = json.load(open(sys.argv[2]))
print(sys.argv[1].ljust(24), ' '.join('%s %.3f (%.2f, %.2f)' % (x['name'], x['grays_per_s'], x.get('leaves_per_ray', 0), x.get('splat_tests_per_ray', 0)) for x in j['scenarios']))
PY
}
for shape in room sphere; do
  $bin/prt-synth $shape -n 1000000 -o $w/$shape.pool --quiet && $bin/prt-radii $w/$shape.pool -o $w/$shape.pool --quiet \
    && $bin/prt-octree $w/$shape.pool -o $w/$shape.pool --quiet && $bin/prt-cull $w/$shape.pool -o $w/$shape.pool --quiet || echo "pool $shape failed"
  for bs in 131072 32768; do $bin/prt-bricks $w/$shape.pool -o $w/$shape-$bs.pool --brick-splats $bs --keep-float --quiet --stats-json $w/bj.json || echo "bricks $shape failed"; python3 -c "import json; j=json.load(open('$w/bj.json')); print('$shape $bs:', j.get('bricks'), 'bricks')"; done
  cam=""; [ $shape = sphere ] && cam="--eye 0,0,3 --look-at 0,0,0 --up 0,1,0 --fov 45"
  for mode in float 131072 32768; do
    extra="--bricks"; pool=$w/$shape-$mode.pool; [ $mode = float ] && { extra=""; pool=$w/$shape-131072.pool; }
    $bin/prt-bench --backend cuda $pool $cam $extra --scenarios primary,shadow,reflect4,full4 --frames 30 --warmup 5 --quiet --json $w/b.json >/dev/null 2>$w/be.txt || { echo "$shape $mode failed"; tail -2 $w/be.txt; continue; }
    summ "$shape $mode" $w/b.json
  done
done
echo "ALL_DONE $((SECONDS - t0)) s"
