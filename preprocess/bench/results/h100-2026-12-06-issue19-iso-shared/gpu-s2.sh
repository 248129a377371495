#!/usr/bin/env bash
# Issue 19 (s2): splat frames with secondary rays on the splat kernel whose closest hits and shadow
# rays share one walk loop (render.h trace_ray_shared, splat.h splat_query) against main's prt-bench,
# alternating, each scenario alone in its own process, two rounds: prt-bench's room, the culled room
# (bench_room.json), the culled 10M sphere; primary and shadow as a check (their kernels are not
# changed). Then this tree's prt_runtime_gpu_tests. Carried: build-ab/tools.tar.xz (main's tools,
# kall/), build-ab/new2-prt-bench.xz (this tree), build-ab/tests.tar.xz (this tree's GPU test program
# and the surface tools it runs).
NAME=s2 TARS="tools.tar.xz tests.tar.xz"
source preprocess/bench/results/h100-2026-12-05-issue17-radii-neighbours/lib500.sh
x=$kall; q=--quiet
$x/prt-bench --backend cuda --save-pool $w/room.pool --frames 1 --warmup 0 --scenarios primary $q > /dev/null 2>&1
$x/prt-cull $w/room.pool -o $w/croom.pool $q
$x/prt-synth sphere -n 10000000 -o $w/s10.pool $q && $x/prt-radii $w/s10.pool -o $w/s10.pool --backend cuda $q \
  && $x/prt-octree $w/s10.pool -o $w/s10.pool $q && $x/prt-cull $w/s10.pool -o $w/cs10.pool $q
echo "pools done $((SECONDS - t0)) s"
xz -dc build-ab/new2-prt-bench.xz > /tmp/prt-bench-new && chmod +x /tmp/prt-bench-new; new=/tmp/prt-bench-new
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
for r in 1 2; do
  for cfg in main new; do
    b=$x/prt-bench; [ $cfg = new ] && b=$new
    alone "r$r prt-bench room, $cfg" $b primary,shadow,reflect4,full4
    alone "r$r culled room (bench_room.json), $cfg" $b primary,shadow,reflect4,full4 $w/croom.pool $room
    alone "r$r culled sphere10m, $cfg" $b reflect4,full4 $w/cs10.pool $sph
  done
done
echo "bench done $((SECONDS - t0)) s"
mkdir -p $root/build-cu && ln -sfn "$kall" $root/build-cu/bin
cp /tmp/ab/t/* $kall/
PRT_BIN_DIR=$kall timeout 300 $kall/prt_runtime_gpu_tests > $out/prt_runtime_gpu_tests-s2.log 2>&1
echo "prt_runtime_gpu_tests rc $? $(grep -E '^\[  (PASSED|FAILED|SKIPPED)' $out/prt_runtime_gpu_tests-s2.log | tr '\n' ' ')"
grep -B2 -A6 "Failure" $out/prt_runtime_gpu_tests-s2.log | head -30
echo "ALL_DONE $((SECONDS - t0)) s"
