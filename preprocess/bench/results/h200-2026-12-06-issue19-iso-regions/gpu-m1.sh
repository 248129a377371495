#!/usr/bin/env bash
# Issue 19 (m1): macro-regions over the ISO's tree. One binary (main 42bdf6a + the ISO regions),
# --empty-space none (the ISO walk of main: no regions) against regions (the new default), each
# scenario alone in its own process, two alternating rounds; then every GPU test program.
NAME=m1 TARS=kall.tar.xz
source preprocess/bench/results/h100-2026-12-05-issue17-radii-neighbours/lib500.sh

x=$kall; q=--quiet
$x/prt-bench --backend cuda --save-pool $w/room.pool --frames 1 --warmup 0 --scenarios primary $q > /dev/null 2>&1
$x/prt-cull $w/room.pool -o $w/croom.pool $q && /usr/bin/time -f "prt-iso room %e s" $x/prt-iso $w/croom.pool -o $w/iroom.pool $q
$x/prt-synth sphere -n 10000000 -o $w/s10.pool $q && $x/prt-radii $w/s10.pool -o $w/s10.pool --backend cuda $q \
  && $x/prt-octree $w/s10.pool -o $w/s10.pool $q && $x/prt-cull $w/s10.pool -o $w/cs10.pool $q \
  && /usr/bin/time -f "prt-iso sphere10m %e s" $x/prt-iso $w/cs10.pool -o $w/is10.pool $q
echo "pools done $((SECONDS - t0)) s"
alone() {  # alone LABEL SCENARIOS ARGS...: each scenario in its own process
  local label=$1 scs=$2; shift 2; local line="$label"
  for sc in ${scs//,/ }; do
    $x/prt-bench --backend cuda --frames 30 --warmup 5 --json $w/b.json "$@" --scenarios $sc > /dev/null 2> $w/err.txt \
      || { line="$line $sc failed: $(tail -1 $w/err.txt)"; continue; }
    line="$line $(python3 -c "import json; s=json.load(open('$w/b.json'))['scenarios'][0]; print('%s %.3f [%.1f l %.1f e]' % (s['name'], s['grays_per_s'], s['leaves_per_ray'], s['splat_tests_per_ray']))")"
  done
  echo "$line"
}
sph="--eye 0,0,3 --look-at 0,0,0 --up 0,1,0 --fov 45"; room="--scene preprocess/bench/bench_room.json"
for r in 1 2; do
  for e in none regions; do
    alone "r$r iso culled room (pool's view), $e" primary,shadow,reflect4,full4 $w/iroom.pool --surface iso --empty-space $e
    alone "r$r iso culled room (bench_room.json), $e" primary,full4 $w/iroom.pool $room --surface iso --empty-space $e
    alone "r$r iso sphere10m, $e" primary,shadow,full4 $w/is10.pool $sph --surface iso --empty-space $e
  done
done
echo "bench done $((SECONDS - t0)) s"
gpu_tests
echo "ALL_DONE $((SECONDS - t0)) s"
