#!/usr/bin/env bash
# Issue 17: how much of the bricks' gap to the float octree is the float walk's node boxes: the float
# octree with and without them (v0's prt-bench, --no-node-boxes), the landed prt-bench's bricks.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/n5.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; t0=$SECONDS
root=$PWD; rm -rf /tmp/ab; mkdir -p /tmp/ab; python3 -c "import tarfile; tarfile.open('build-ab/pack3.tar.xz').extractall('/tmp/ab')"
new=/tmp/ab/new; w=/tmp/n5; rm -rf $w; mkdir -p $w; q=--quiet
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
print(sys.argv[1].ljust(10), sys.argv[2].ljust(8), ' '.join('%s %.3f (%.1f)' % (x['name'], x['grays_per_s'], x.get('leaves_per_ray', 0)) for x in j['scenarios']), flush=True)
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
    bench "r$round $shape" float /tmp/ab/v0/prt-bench $p "${a[@]}"
    bench "r$round $shape" float-nobox /tmp/ab/v0/prt-bench $p --no-node-boxes "${a[@]}"
    bench "r$round $shape" bricks /tmp/ab/old/prt-bench $p --bricks "${a[@]}"
  done
done
echo "ALL_DONE $((SECONDS - t0)) s"
