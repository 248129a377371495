#!/bin/bash
# Issue 19/17: bricks against float after the splat loop change. Two trees side by side: head
# (HEAD: brick walk on closest_in_leaf / any_in_leaf) and b1 (the working tree: the brick any-hit
# loops written out, as any_hit_splats). Culled 1M sphere and 1M room, both layouts.
set -uo pipefail
OUT=${OUT:-/tmp/out}; mkdir -p "$OUT"; exec > >(tee "$OUT/r6.txt") 2>&1
nvidia-smi --query-gpu=name,clocks.sm,clocks.max.sm --format=csv,noheader
F="-DCMAKE_PREFIX_PATH=$PWD/.device-deps/usr -DPRT_WITH_PCL=OFF -DPRT_WITH_OPENMESH=OFF -DPRT_WITH_OIIO=OFF -DPRT_WITH_PYTHON=OFF -DPRT_WITH_GLFW=OFF -DCMAKE_BUILD_TYPE=Release"
T="prt-bench prt-synth prt-radii prt-octree prt-cull prt-bricks prt-play"
t0=$SECONDS
mkdir -p /tmp/thead && tar -xzf .device-deps/head.tar.gz -C /tmp/thead
( cmake -S /tmp/thead -B /tmp/bhead $F >/tmp/h.cmake.txt 2>&1 && cmake --build /tmp/bhead -j8 --target $T >/tmp/h.build.txt 2>&1 || { echo "FAIL head"; grep error /tmp/h.build.txt | head; } ) & p1=$!
( cmake -S . -B /tmp/bb1 $F >/tmp/b.cmake.txt 2>&1 && cmake --build /tmp/bb1 -j8 --target $T >/tmp/b.build.txt 2>&1 || { echo "FAIL b1"; grep error /tmp/b.build.txt | head; } ) & p2=$!
wait $p1 $p2
echo "built in $((SECONDS - t0)) s"
w=/tmp/w; mkdir -p $w; bin=/tmp/bhead/bin
for shape in sphere room; do
  $bin/prt-synth $shape -n 1000000 -o $w/$shape.pool --quiet && $bin/prt-radii $w/$shape.pool -o $w/$shape.pool --quiet \
    && $bin/prt-octree $w/$shape.pool -o $w/$shape.pool --quiet && $bin/prt-cull $w/$shape.pool -o $w/$shape.pool --quiet \
    && $bin/prt-bricks $w/$shape.pool -o $w/$shape-b.pool --keep-float --keep-points --quiet || echo "pool $shape failed"
done
echo "pools at $((SECONDS - t0)) s"
for rep in 1 2; do for shape in sphere room; do
  cam=""; [ $shape = sphere ] && cam="--eye 0,0,3 --look-at 0,0,0 --up 0,1,0 --fov 45"
  for v in head b1; do
    for mode in float bricks; do
      extra=""; [ $mode = bricks ] && extra="--bricks"
      /tmp/b$v/bin/prt-bench --backend cuda $w/$shape-b.pool $cam $extra --scenarios primary,shadow,reflect4,full4 --frames 50 --warmup 10 --quiet --json $w/b.json >/dev/null 2>$w/be.txt || { echo "$shape $v $mode failed"; tail -2 $w/be.txt; continue; }
      cp $w/b.json $OUT/$shape-$v-$mode-r$rep.json
      python3 - "$shape $v $mode" $w/b.json <<'PY'
import json, sys
j = json.load(open(sys.argv[2]))
print(sys.argv[1].ljust(22), ' '.join('%s %.3f (%.2f, %.2f)' % (x['name'], x['grays_per_s'], x.get('leaves_per_ray', 0), x.get('splat_tests_per_ray', 0)) for x in j['scenarios']))
PY
    done
  done
done; done
for v in head b1; do
  /tmp/b$v/bin/prt-play $w/room-b.pool --bricks --headless --backend cuda --width 512 --height 512 --out /tmp/img-$v.ppm -q >/tmp/p.txt 2>&1 || tail -2 /tmp/p.txt
done
sha1sum /tmp/img-*.ppm
echo "ALL_DONE $((SECONDS - t0)) s"
