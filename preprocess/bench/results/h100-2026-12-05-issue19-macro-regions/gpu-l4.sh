#!/usr/bin/env bash
# Issue 19 (l4): main (b52ac8e) against macro-regions (the landed default), prt-bench alone per
# scenario, two rounds, on whatever GPU the device tool lends (an H200 wanted, for the README rows).
NAME=l4 TARS=kall.tar.xz
source preprocess/bench/results/h100-2026-12-05-issue17-radii-neighbours/lib500.sh

x=$kall; q=--quiet
$x/prt-bench --backend cuda --save-pool $w/room32.pool --frames 1 --warmup 0 --scenarios primary $q > /dev/null 2>&1
$x/prt-cull $w/room32.pool -o $w/croom32.pool $q
$x/prt-synth sphere -n 10000000 -o $w/s10.pool $q && $x/prt-radii $w/s10.pool -o $w/s10.pool --backend cuda $q \
  && $x/prt-octree $w/s10.pool -o $w/s10.pool $q && $x/prt-cull $w/s10.pool -o $w/cs10.pool $q
$x/prt-synth sphere -n 1000000 -o $w/s1.pool $q && $x/prt-radii $w/s1.pool -o $w/s1.pool $q \
  && $x/prt-octree $w/s1.pool -o $w/s1.pool $q && $x/prt-cull $w/s1.pool -o $w/cs1.pool $q
echo "pools done $((SECONDS - t0)) s"
alone() {  # alone LABEL BINARY SCENARIOS ARGS...: each scenario in its own process
  local label=$1 bin=$2 scs=$3; shift 3; local line="$label"
  for sc in ${scs//,/ }; do
    $bin --backend cuda --frames 30 --warmup 5 --json $w/b.json "$@" --scenarios $sc > /dev/null 2> $w/err.txt \
      || { line="$line $sc failed: $(tail -1 $w/err.txt)"; continue; }
    line="$line $(python3 -c "import json; s=json.load(open('$w/b.json'))['scenarios'][0]; print('%s %.3f [%.1f l %.1f t]' % (s['name'], s['grays_per_s'], s['leaves_per_ray'], s['splat_tests_per_ray']))")"
  done
  echo "$line"
}
sph="--eye 0,0,3 --look-at 0,0,0 --up 0,1,0 --fov 45"; room="--scene preprocess/bench/bench_room.json"
xz -dc build-ab/base/prt-bench.xz > /tmp/prt-bench-base && chmod +x /tmp/prt-bench-base; base=/tmp/prt-bench-base
for r in 1 2; do
  for cfg in base regions; do
    if [ "$cfg" = base ]; then b=$base; k="main b52ac8e"; e=""; else b=$x/prt-bench; k="--empty-space $cfg"; e="--empty-space $cfg"; fi
    alone "r$r culled room, $k" $b primary,shadow,reflect4,full4 $w/croom32.pool $room $e
    alone "r$r sphere10m, $k" $b primary,shadow,reflect4 $w/cs10.pool $sph $e
    alone "r$r default room, $k" $b primary,shadow,reflect4,full4 $e
    alone "r$r sphere1m, $k" $b primary,shadow,reflect4 $w/cs1.pool $sph $e
  done
done
echo "ALL_DONE $((SECONDS - t0)) s"
