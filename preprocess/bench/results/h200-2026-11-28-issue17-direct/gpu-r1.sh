#!/bin/bash
# Issue 17: direct bricks (splats in leaf order, no references) against referenced bricks and the
# float octree. Culled 1M sphere and 1M room; each built with prt-bricks --direct never (referenced,
# the layout before) and --direct smaller (the default); prt-bench on each pool, rounds interleaved.
set -uo pipefail
OUT=${OUT:-/tmp/out}; mkdir -p "$OUT"; exec > >(tee "$OUT/r1.txt") 2>&1
nvidia-smi --query-gpu=name,clocks.sm,clocks.max.sm --format=csv,noheader
F="-DCMAKE_PREFIX_PATH=$PWD/.device-deps/usr -DPRT_WITH_PCL=OFF -DPRT_WITH_OPENMESH=OFF -DPRT_WITH_OIIO=OFF -DPRT_WITH_PYTHON=OFF -DPRT_WITH_GLFW=OFF -DCMAKE_BUILD_TYPE=Release"
T="prt-bench prt-synth prt-radii prt-octree prt-cull prt-bricks prt-play"
t0=$SECONDS
cmake -S . -B build-dev $F >/tmp/c.txt 2>&1 && cmake --build build-dev -j16 --target $T >/tmp/b.txt 2>&1 || { echo "BUILD FAIL"; grep -E "error" /tmp/b.txt | head -20; exit 1; }
echo "built in $((SECONDS - t0)) s"
w=/tmp/w; mkdir -p $w; bin=build-dev/bin
for shape in sphere room; do
  $bin/prt-synth $shape -n 1000000 -o $w/$shape.pool --quiet && $bin/prt-radii $w/$shape.pool -o $w/$shape.pool --quiet \
    && $bin/prt-octree $w/$shape.pool -o $w/$shape.pool --quiet && $bin/prt-cull $w/$shape.pool -o $w/$shape.pool --quiet || echo "pool $shape failed"
  for d in never smaller; do
    $bin/prt-bricks $w/$shape.pool -o $w/$shape-$d.pool --direct $d --keep-float --keep-points --stats-json $OUT/bricks-$shape-$d.json 2>&1 | grep -E "bricks \(|B per point" || echo "bricks $shape $d failed"
  done
done
echo "pools at $((SECONDS - t0)) s"
for rep in 1 2; do for shape in sphere room; do
  cam=""; [ $shape = sphere ] && cam="--eye 0,0,3 --look-at 0,0,0 --up 0,1,0 --fov 45"
  for mode in float never smaller; do
    pool=$w/$shape-$mode.pool; extra="--bricks"
    [ $mode = float ] && { pool=$w/$shape-smaller.pool; extra=""; }
    $bin/prt-bench --backend cuda $pool $cam $extra --scenarios primary,shadow,reflect4,full4 --frames 50 --warmup 10 --quiet --json $w/b.json >/dev/null 2>$w/be.txt || { echo "$shape $mode failed"; tail -2 $w/be.txt; continue; }
    cp $w/b.json $OUT/$shape-$mode-r$rep.json
    python3 - "$shape $mode r$rep" $w/b.json <<'PY'
import json, sys
j = json.load(open(sys.argv[2]))
print(sys.argv[1].ljust(22), ' '.join('%s %.3f (%.2f, %.2f)' % (x['name'], x['grays_per_s'], x.get('leaves_per_ray', 0), x.get('splat_tests_per_ray', 0)) for x in j['scenarios']))
PY
  done
done; done
for shape in sphere room; do for d in never smaller; do
  $bin/prt-play $w/$shape-$d.pool --bricks --headless --backend cuda --width 512 --height 512 --out /tmp/img-$shape-$d.ppm -q >/tmp/p.txt 2>&1 || tail -2 /tmp/p.txt
  $bin/prt-play $w/$shape-$d.pool --bricks --headless --backend cuda --width 512 --height 512 --max-bounces 4 --out /tmp/imgr-$shape-$d.ppm -q >/tmp/p.txt 2>&1 || tail -2 /tmp/p.txt
done; done
sha1sum /tmp/img-*.ppm /tmp/imgr-*.ppm
echo "ALL_DONE $((SECONDS - t0)) s"
