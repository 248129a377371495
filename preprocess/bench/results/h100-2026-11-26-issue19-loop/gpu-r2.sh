#!/bin/bash
# Issue 19: the splat kernel's loop shape. Three trees built side by side: head (HEAD's splat.h),
# v1 (the working tree: closest_in_walk with pass 1 / pass 2 written out in its loop), v2 (81d1185's
# closest_hit_splats / any_hit_splats bodies in HEAD's splat.h). Same host, interleaved rounds.
set -uo pipefail
OUT=${OUT:-/tmp/out}
mkdir -p "$OUT"
exec > >(tee "$OUT/r2.txt") 2>&1
nvidia-smi --query-gpu=name,clocks.sm,clocks.max.sm --format=csv,noheader
F="-DCMAKE_PREFIX_PATH=$PWD/.device-deps/usr -DPRT_WITH_PCL=OFF -DPRT_WITH_OPENMESH=OFF -DPRT_WITH_OIIO=OFF -DPRT_WITH_PYTHON=OFF -DPRT_WITH_GLFW=OFF -DCMAKE_BUILD_TYPE=Release"
t0=$SECONDS
S=runtime/core/include/prt/core/splat.h
for v in head v2; do
  mkdir -p /tmp/t$v && tar --exclude=./build-dev --exclude=./.device-deps/old -cf - . | tar -xf - -C /tmp/t$v
done
cp .device-deps/splat_head.h /tmp/thead/$S
cp .device-deps/splat_v2.h /tmp/tv2/$S
ln -sfn $PWD /tmp/tv1
pids=""
for v in head v1 v2; do
  ( cmake -S /tmp/t$v -B /tmp/b$v $F >/tmp/$v.cmake.txt 2>&1 && cmake --build /tmp/b$v -j6 --target prt-bench prt-play >/tmp/$v.build.txt 2>&1 || { echo "BUILD FAIL $v"; grep -E "error" /tmp/$v.build.txt | head; } ) &
  pids="$pids $!"
done
wait $pids
echo "built in $((SECONDS - t0)) s"
/tmp/bhead/bin/prt-bench --save-pool /tmp/room.pool --scenarios primary --frames 3 -q >/dev/null 2>&1; echo "save rc $?"
summ() { python3 -c "
import json,sys; d = json.load(open('$1'))
print('$2', [(s.get('name'), round(s['grays_per_s'], 3), round(s.get('leaves_per_ray', 0), 2), round(s.get('splat_tests_per_ray', 0), 2)) for s in d['scenarios']])" 2>&1 | tail -1; }
for round in 1 2; do
  for v in head v1 v2; do
    rm -f /tmp/r.json
    /tmp/b$v/bin/prt-bench --scenarios primary,shadow,reflect4,full4 --frames 50 -q --json /tmp/r.json >/tmp/run.txt 2>&1 || tail -2 /tmp/run.txt
    cp /tmp/r.json $OUT/bench-$v-r$round.json
    summ /tmp/r.json "$v synthetic r$round"
  done
done
for v in head v1 v2; do
  rm -f /tmp/r.json
  /tmp/b$v/bin/prt-bench /tmp/room.pool --scenarios primary,shadow --frames 50 -q --json /tmp/r.json >/tmp/run.txt 2>&1 || tail -2 /tmp/run.txt
  summ /tmp/r.json "$v pool"
  /tmp/b$v/bin/prt-play /tmp/room.pool --headless --backend cuda --width 512 --height 512 --out /tmp/img-$v.ppm -q >/tmp/play.txt 2>&1 || tail -3 /tmp/play.txt
  /tmp/b$v/bin/prt-play /tmp/room.pool --headless --backend cuda --width 512 --height 512 --max-bounces 4 --out /tmp/imgr-$v.ppm -q >/tmp/play.txt 2>&1 || tail -3 /tmp/play.txt
done
sha1sum /tmp/img-*.ppm /tmp/imgr-*.ppm
echo "ALL_DONE $((SECONDS - t0)) s"
