#!/usr/bin/env bash
# Issue 19 (m2): is m1's ISO without regions (--empty-space none) as fast as before the splat
# walk's macro-regions (main b52ac8e, whose walk has no region arithmetic)? Three prt-bench
# binaries in turn, each scenario alone in its own process, two rounds: b52ac8e, this tree with
# --empty-space none, this tree (regions, the default).
NAME=m2 TARS=kall.tar.xz
source preprocess/bench/results/h100-2026-12-05-issue17-radii-neighbours/lib500.sh

x=$kall; q=--quiet
$x/prt-bench --backend cuda --save-pool $w/room.pool --frames 1 --warmup 0 --scenarios primary $q > /dev/null 2>&1
$x/prt-cull $w/room.pool -o $w/croom.pool $q && $x/prt-iso $w/croom.pool -o $w/iroom.pool $q
$x/prt-synth sphere -n 10000000 -o $w/s10.pool $q && $x/prt-radii $w/s10.pool -o $w/s10.pool --backend cuda $q \
  && $x/prt-octree $w/s10.pool -o $w/s10.pool $q && $x/prt-cull $w/s10.pool -o $w/cs10.pool $q \
  && $x/prt-iso $w/cs10.pool -o $w/is10.pool $q
echo "pools done $((SECONDS - t0)) s"
alone() {  # alone LABEL BINARY SCENARIOS ARGS...: each scenario in its own process
  local label=$1 bin=$2 scs=$3; shift 3; local line="$label"
  for sc in ${scs//,/ }; do
    $bin --backend cuda --frames 30 --warmup 5 --json $w/b.json "$@" --scenarios $sc > /dev/null 2> $w/err.txt \
      || { line="$line $sc failed: $(tail -1 $w/err.txt)"; continue; }
    line="$line $(python3 -c "import json; s=json.load(open('$w/b.json'))['scenarios'][0]; print('%s %.3f [%.1f l %.1f e]' % (s['name'], s['grays_per_s'], s['leaves_per_ray'], s['splat_tests_per_ray']))")"
  done
  echo "$line"
}
sph="--eye 0,0,3 --look-at 0,0,0 --up 0,1,0 --fov 45"; room="--scene preprocess/bench/bench_room.json"
xz -dc build-ab/base-prt-bench.xz > /tmp/prt-bench-base && chmod +x /tmp/prt-bench-base; base=/tmp/prt-bench-base
for r in 1 2; do
  for cfg in base none regions; do
    if [ "$cfg" = base ]; then b=$base; e=""; k="main b52ac8e"; else b=$x/prt-bench; e="--empty-space $cfg"; k="$e"; fi
    alone "r$r iso culled room (pool's view), $k" $b primary,shadow,full4 $w/iroom.pool --surface iso $e
    alone "r$r iso culled room (bench_room.json), $k" $b primary,full4 $w/iroom.pool $room --surface iso $e
    alone "r$r iso sphere10m, $k" $b primary,full4 $w/is10.pool $sph --surface iso $e
    alone "r$r splats culled room (bench_room.json), $k" $b primary,full4 $w/croom.pool $room $e
  done
done
echo "ALL_DONE $((SECONDS - t0)) s"
