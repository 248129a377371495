#!/usr/bin/env bash
# Issue 19 (s1): ISO frames with secondary rays on an ISO-only kernel whose closest hits and shadow
# rays share one walk loop (render.h trace_ray_shared) at 3 and 4 blocks per SM, against the general
# kernel those frames ran on (PRT_EXP_ISO_GENERAL=1 in this experimental build). Each scenario alone
# in its own process, two rounds. Carried: build-ab/tools.tar.xz (main's tools, kall/),
# build-ab/new-prt-bench.xz (this tree), build-ab/tests.tar.xz (prt_runtime_gpu_tests, this tree).
NAME=s1 TARS="tools.tar.xz tests.tar.xz"
source preprocess/bench/results/h100-2026-12-05-issue17-radii-neighbours/lib500.sh
x=$kall; q=--quiet
$x/prt-bench --backend cuda --save-pool $w/room.pool --frames 1 --warmup 0 --scenarios primary $q > /dev/null 2>&1
$x/prt-cull $w/room.pool -o $w/croom.pool $q && $x/prt-iso $w/croom.pool -o $w/iroom.pool $q
$x/prt-synth sphere -n 10000000 -o $w/s10.pool $q && $x/prt-radii $w/s10.pool -o $w/s10.pool --backend cuda $q \
  && $x/prt-octree $w/s10.pool -o $w/s10.pool $q && $x/prt-cull $w/s10.pool -o $w/cs10.pool $q \
  && $x/prt-iso $w/cs10.pool -o $w/is10.pool $q
echo "pools done $((SECONDS - t0)) s"
xz -dc build-ab/new-prt-bench.xz > /tmp/prt-bench-new && chmod +x /tmp/prt-bench-new; new=/tmp/prt-bench-new
alone() {  # alone LABEL SCENARIOS ARGS...: each scenario in its own process (the new binary)
  local label=$1 scs=$2; shift 2; local line="$label"
  for sc in ${scs//,/ }; do
    $new --backend cuda --frames 30 --warmup 5 --json $w/b.json "$@" --scenarios $sc > /dev/null 2> $w/err.txt \
      || { line="$line $sc failed: $(tail -1 $w/err.txt)"; continue; }
    line="$line $(python3 -c "import json; s=json.load(open('$w/b.json'))['scenarios'][0]; print('%s %.3f [%.1f l]' % (s['name'], s['grays_per_s'], s['leaves_per_ray']))")"
  done
  echo "$line"
}
sph="--eye 0,0,3 --look-at 0,0,0 --up 0,1,0 --fov 45"; room="--scene preprocess/bench/bench_room.json"
for r in 1 2; do
  for cfg in general shared3 shared4; do
    g=0; mb=""; [ $cfg = general ] && g=1; [ $cfg = shared4 ] && mb="--min-blocks 4"
    export PRT_EXP_ISO_GENERAL=$g
    alone "r$r iso culled room (pool's view), $cfg" reflect4,full4 $w/iroom.pool --surface iso $mb
    alone "r$r iso culled room (bench_room.json), $cfg" reflect4,full4 $w/iroom.pool $room --surface iso $mb
    alone "r$r iso sphere10m, $cfg" full4 $w/is10.pool $sph --surface iso $mb
  done
done
unset PRT_EXP_ISO_GENERAL
echo "bench done $((SECONDS - t0)) s"
mkdir -p $root/build-cu && ln -sfn "$kall" $root/build-cu/bin
cp /tmp/ab/t/* $kall/
PRT_BIN_DIR=$kall timeout 300 $kall/prt_runtime_gpu_tests > $out/prt_runtime_gpu_tests.log 2>&1
echo "prt_runtime_gpu_tests rc $? $(grep -E '^\[  (PASSED|FAILED|SKIPPED)' $out/prt_runtime_gpu_tests.log | tr '\n' ' ')"
grep -B2 -A6 "Failure" $out/prt_runtime_gpu_tests.log | head -30
echo "ALL_DONE $((SECONDS - t0)) s"
