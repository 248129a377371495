#!/usr/bin/env bash
# Issue 17 on the GPU host (one H200): node boxes in bricks (bricks.h descend_bricked, built at load by
# rt::build_brick_node_boxes). GPU suites first (the gtest binaries built on the dev VM), then the
# bricked pools against the float octree on the culled 1M room and sphere (b1's method, 2026-11-29),
# and the bench room scene: float, bricks, bricks --no-node-boxes, the landed prt-bench (old) alternating.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/n1.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; nproc; t0=$SECONDS
root=$PWD; rm -rf /tmp/ab; mkdir -p /tmp/ab; python3 -c "import tarfile; tarfile.open('build-ab/pack.tar.xz').extractall('/tmp/ab')"
new=/tmp/ab/new; old=/tmp/ab/old/prt-bench; w=/tmp/n1; rm -rf $w; mkdir -p $w; q=--quiet
mkdir -p /work/main/build-cu && ln -sfn "$new" /work/main/build-cu/bin
export PRT_BIN_DIR=$new
for t in prt_runtime_gpu_tests prt_brick_stream_gpu_tests prt_stability_gpu_tests; do
  timeout 150 /tmp/ab/tests/$t --gtest_filter='-*Window*' > $w/$t.log 2>&1
  echo "$t: rc $? $(grep -E '^\[  (PASSED|FAILED|SKIPPED) |tests? from .* ran' $w/$t.log | tr '\n' ' ')"
  grep -E "Failure|FAILED  \]" $w/$t.log | head -6
done
cp $w/prt_brick_stream_gpu_tests.log "$out/" 2>/dev/null
echo "tests done $((SECONDS - t0)) s"
for shape in room sphere; do
  $new/prt-synth $shape -n 1000000 -o $w/$shape.pool $q && $new/prt-radii $w/$shape.pool -o $w/$shape.pool --backend cuda $q \
    && $new/prt-octree $w/$shape.pool -o $w/$shape.pool $q && $new/prt-cull $w/$shape.pool -o $w/$shape.pool $q \
    && $new/prt-bricks $w/$shape.pool -o $w/$shape-b.pool --keep-float $q || echo "pool $shape failed"
done
$new/prt-bench --save-pool $w/broom.pool --frames 1 --warmup 0 --width 16 --height 16 --scenarios primary $q > /dev/null
$new/prt-cull $w/broom.pool -o $w/bculled.pool $q && $new/prt-bricks $w/bculled.pool -o $w/bc-b.pool --keep-float $q
sed 's/"room.pool"/"bc-b.pool"/' $root/preprocess/bench/bench_room.json > $w/scene_c.json
echo "pools done $((SECONDS - t0)) s"
bench() {  # bench LABEL VARIANT BIN ARGS...
  local label=$1 v=$2 bin=$3; shift 3
  $bin --backend cuda --frames 30 --warmup 5 --json $w/b.json "$@" > /dev/null 2> $w/err.txt \
    || { echo "$label $v failed: $(tail -2 $w/err.txt)"; return; }
  python3 - "$label" "$v" $w/b.json <<'PY'
import json, sys
j = json.load(open(sys.argv[3]))
print(sys.argv[1].ljust(10), sys.argv[2].ljust(12), ' '.join('%s %.3f (%.1f)' % (x['name'], x['grays_per_s'], x.get('leaves_per_ray', 0)) for x in j['scenarios']), flush=True)
PY
}
cam="--eye 0,0,3 --look-at 0,0,0 --up 0,1,0 --fov 45"
for round in 1 2; do
  for shape in room sphere bench; do
    case $shape in
      room) p=$w/room-b.pool; a=(--scenarios primary,shadow,reflect4,full4);;
      sphere) p=$w/sphere-b.pool; a=($cam --scenarios primary,shadow,reflect4);;
      bench) p=$w/bc-b.pool; a=(--scene $w/scene_c.json --scenarios primary,shadow,reflect4,full4);;
    esac
    bench "r$round $shape" float $new/prt-bench $p "${a[@]}"
    bench "r$round $shape" bricks-old $old $p --bricks "${a[@]}"
    bench "r$round $shape" bricks-nobox $new/prt-bench $p --bricks --no-node-boxes "${a[@]}"
    bench "r$round $shape" bricks $new/prt-bench $p --bricks "${a[@]}"
  done
done
# images: bricks with and without boxes, CUDA and CPU, byte-equal expected within a backend
for v in box nobox; do
  extra=""; [ $v = nobox ] && extra=--no-node-boxes
  for be in cuda cpu; do $new/prt-play $w/bc-b.pool --scene $w/scene_c.json --bricks $extra --backend $be --out $w/img-$v-$be.ppm $q; done
done
cmp $w/img-box-cuda.ppm $w/img-nobox-cuda.ppm && echo "cuda images equal"; cmp $w/img-box-cpu.ppm $w/img-nobox-cpu.ppm && echo "cpu images equal"
echo "ALL_DONE $((SECONDS - t0)) s"
