#!/usr/bin/env bash
# Issue 19 on the GPU host (one H200), 2026-12-01, after gpu-c2.sh in the same machine (build-gpu):
# the device walk dividing (PRT_DEVICE_WALK_RCP=0, the default) against multiplying by the walk's
# 1 / d as the host does (=1), prt-bench 1024x1024 on the culled 1M room and sphere, float octree and
# bricks, alternating, two rounds; then the GPU suites built with =1.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/c3.txt") 2>&1
t0=$SECONDS; bin=$PWD/build-gpu/bin; w=/tmp/w3; mkdir -p $w
for shape in room sphere; do
  $bin/prt-synth $shape -n 1000000 -o $w/$shape.pool --quiet && $bin/prt-radii $w/$shape.pool -o $w/$shape.pool --quiet \
    && $bin/prt-octree $w/$shape.pool -o $w/$shape.pool --quiet && $bin/prt-cull $w/$shape.pool -o $w/$shape.pool --quiet \
    && $bin/prt-bricks $w/$shape.pool -o $w/$shape-b.pool --keep-float --quiet || echo "pool $shape failed"
done
cp $bin/prt-bench $w/div-bench
cmake -S . -B build-gpu -DCMAKE_CUDA_FLAGS=-DPRT_DEVICE_WALK_RCP=1 > $out/configure3.log 2>&1 \
  && cmake --build build-gpu -j 16 > $out/build3.log 2>&1 || { echo "build failed"; tail -20 $out/build3.log; }
echo "build done $((SECONDS - t0)) s"
sm() { python3 -c 'import json,sys; j=json.load(open(sys.argv[2])); print(sys.argv[1].ljust(22), " ".join("%s %.3f" % (x["name"], x["grays_per_s"]) for x in j["scenarios"]))' "$1" "$2"; }
for round in 1 2; do
  for shape in room sphere; do
    c=""; sc="primary,shadow,reflect4,full4"; [ $shape = sphere ] && { c="--eye 0,0,3 --look-at 0,0,0 --up 0,1,0 --fov 45"; sc="primary,shadow"; }
    for mode in float bricks; do
      extra="--bricks"; [ $mode = float ] && extra=""
      for who in div rcp; do
        b=$bin/prt-bench; [ $who = div ] && b=$w/div-bench
        $b --backend cuda $w/$shape-b.pool $c $extra --scenarios $sc --frames 30 --warmup 5 --quiet --json $w/b.json >/dev/null 2>$w/be.txt || { echo "$shape $mode $who failed"; tail -2 $w/be.txt; continue; }
        sm "r$round $shape $mode $who" $w/b.json
      done
    done
  done
done
echo "bench done $((SECONDS - t0)) s"
ctest --test-dir build-gpu -L gpu --output-on-failure --timeout 300 > $out/gpu-tests3.log 2>&1
grep -E "tests passed|tests failed|Failed|\(Skipped\)" $out/gpu-tests3.log | head -20
echo "ALL_DONE $((SECONDS - t0)) s"
