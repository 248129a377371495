#!/usr/bin/env bash
# Issue 19 (H200): heavy items first against the image-order queue on the splat and ISO rows of the
# README: prt-bench's default room, the culled room (bench_room.json's camera), its bricks, ISO on
# the culled room (pool alone), the culled 1M and 10M spheres (z = 3) and ISO on the 10M sphere.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/q5.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; t0=$SECONDS
rm -rf /tmp/ab; mkdir -p /tmp/ab
for p in pack10 pack23; do python3 -c "import tarfile; tarfile.open('build-ab/$p.tar.xz').extractall('/tmp/ab')"; done
n=/tmp/ab/p23; x=/tmp/ab/bin; cp -r /tmp/ab/p10 $x; cp $n/prt-bench $n/prt-play $x/; w=/tmp/q5; mkdir -p $w; q=--quiet
$x/prt-bench --backend cuda --save-pool $w/room.pool --frames 1 --warmup 0 --scenarios primary $q > /dev/null 2>&1
$x/prt-cull $w/room.pool -o $w/culled.pool $q && $x/prt-iso $w/culled.pool -o $w/surf.pool $q
$x/prt-bricks $w/culled.pool -o $w/bricked.pool --keep-float $q
$x/prt-synth sphere -n 1000000 -o $w/s1.pool $q && $x/prt-radii $w/s1.pool -o $w/s1.pool $q && $x/prt-octree $w/s1.pool -o $w/s1.pool $q && $x/prt-cull $w/s1.pool -o $w/s1.pool $q
$x/prt-synth sphere -n 10000000 -o $w/s10.pool $q && $x/prt-radii $w/s10.pool -o $w/s10.pool --backend cuda $q \
  && $x/prt-octree $w/s10.pool -o $w/s10.pool $q && $x/prt-cull $w/s10.pool -o $w/s10.pool $q || echo "sphere failed"
echo "pools done $((SECONDS - t0)) s"
timeout 150 $x/prt-iso $w/s10.pool -o $w/s10iso.pool $q || echo "10M ISO failed or timed out"
echo "10M ISO done $((SECONDS - t0)) s"
bench() {  # bench LABEL ARGS...
  local label=$1; shift
  $x/prt-bench --backend cuda --frames 30 --warmup 5 --json $w/b.json "$@" > /dev/null 2> $w/err.txt \
    || { echo "$label failed: $(tail -2 $w/err.txt)"; return; }
  python3 - "$label" $w/b.json <<'PY'
import json, sys
j = json.load(open(sys.argv[2]))
print(sys.argv[1].ljust(24), ' '.join('%s %.3f (%d)' % (x['name'], x['grays_per_s'], x.get('heavy_first_items', -1)) for x in j['scenarios']), flush=True)
PY
}
sph="--eye 0,0,3 --look-at 0,0,0 --up 0,1,0 --fov 45"; room="--scene preprocess/bench/bench_room.json"
for r in 1 2; do for k in mega-fifo mega; do
  bench "default room $k" --kernel $k --scenarios primary,shadow,reflect4,full4
  bench "culled room $k" $w/culled.pool $room --kernel $k --scenarios primary,shadow,reflect4,full4
  bench "bricks room $k" $w/bricked.pool $room --bricks --kernel $k --scenarios primary,shadow,reflect4,full4
  bench "iso culled $k" $w/surf.pool --surface iso --kernel $k --scenarios primary,shadow,full4
  bench "sphere1m $k" $w/s1.pool $sph --kernel $k --scenarios primary,shadow,reflect4
  bench "sphere10m $k" $w/s10.pool $sph --kernel $k --scenarios primary,shadow,reflect4
  [ -s $w/s10iso.pool ] && bench "sphere10m iso $k" $w/s10iso.pool $sph --surface iso --kernel $k --scenarios primary,shadow,full4
  echo "round $r $k done $((SECONDS - t0)) s"
done; done
echo "ALL_DONE $((SECONDS - t0)) s"
