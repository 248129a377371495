#!/usr/bin/env bash
# Issue 19 (m4): is the ISO walk slower than b52ac8e's because of the region code it carries? The ISO walk
# compiled with no region code at all ("noreg": walk_step without regions, so walk_step_out folds
# the region arithmetic away) against b52ac8e and the landed tree with --empty-space none, two rounds.
NAME=m4 TARS=${TARS:-tools.tar.xz}
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
for v in base cur noreg; do xz -dc build-ab/$v-prt-bench.xz > /tmp/prt-bench-$v && chmod +x /tmp/prt-bench-$v; done
for r in 1 2; do
  for cfg in base cur-none noreg; do
    e=""; case $cfg in base) b=/tmp/prt-bench-base;; cur-none) b=/tmp/prt-bench-cur; e="--empty-space none";; noreg) b=/tmp/prt-bench-noreg;; esac
    alone "r$r iso culled room (pool's view), $cfg" $b primary,shadow,full4 $w/iroom.pool --surface iso $e
    alone "r$r iso culled room (bench_room.json), $cfg" $b primary,full4 $w/iroom.pool $room --surface iso $e
    alone "r$r iso sphere10m, $cfg" $b primary,full4 $w/is10.pool $sph --surface iso $e
  done
done
echo "bench done $((SECONDS - t0)) s"
[ "${GPU_TESTS:-0}" = 1 ] && gpu_tests
echo "ALL_DONE $((SECONDS - t0)) s"
