#!/usr/bin/env bash
# Issue 17 on the GPU host (16 cores, one H200): (1) the build's cell size: a 100M room from
# points with --memory 12G (cells of about 950k points, the 500M build's), 3G and 1.5G; (2) the 500M
# room under an eighth of its pool with the default light inside the room (the camera is inside):
# first image, close view converged, the 100-frame orbit, prt-bench at the close view.
# Usage (repository root): BIN=build-cuda/bin bash .../gpu-s2.sh
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/s2.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; nproc
bin=$(cd "$BIN" && pwd); here=$(cd "$(dirname "$0")" && pwd)
w=/tmp/w500; mkdir -p $w
T='%e s wall, %U user, %S sys, %M KB'
if [ "${SKIP_CELLS:-0}" = 0 ]; then
  $bin/prt-synth room -n 100000000 -o $w/s100.pool --quiet; echo "synth 100M rc $?"
  for m in 12G 3G 1.5G; do
    /usr/bin/time -f "cells $m: $T" $bin/prt-bricks $w/s100.pool -o $w/b100.pool --memory $m --stats-json $out/b100-$m.json 2> $w/b100.err; echo "100M --memory $m rc $?"
    grep -E "cells \(|s partitioning|building \(|wall," $w/b100.err
  done
  rm -f $w/s100.pool $w/b100.pool
fi
s=$SECONDS; $bin/prt-synth room -n 500000000 -o $w/s.pool --quiet; echo "synth 500M: rc $? $((SECONDS - s)) s"
s=$SECONDS; /usr/bin/time -f "bricks: $T" $bin/prt-bricks $w/s.pool -o $w/b.pool --memory 12G --stats-json $out/bricks500.json 2> $w/bricks.err; echo "== bricks from points --memory 12G: rc $? $((SECONDS - s)) s"
grep -v "%" $w/bricks.err | tail -4
rm -f $w/s.pool
cam="--eye 0.05,-0.2,0.2 --look-at -0.3,-0.6,-0.4 --up 0,1,0 --fov 50 --width 1024 --height 1024"
pool=$(stat -c %s $w/b.pool); budget=$(( pool / 8 )); echo "pool $pool B, budget $budget B (pool / 8)"
s=$(date +%s.%N); $bin/prt-play $w/b.pool --backend cuda --gpu-budget $budget $cam --out $w/first.pfm 2>$w/first.err; echo "first image (one pass): $(python3 -c "print(round($(date +%s.%N) - $s, 2))") s wall from process start"; grep -E "light|streaming|frame 0" $w/first.err | head -3
$bin/prt-play $w/b.pool --backend cuda --gpu-budget $budget $cam --converge --out $out/close.ppm 2>$out/conv.err; grep -E "pass\(es\)|converge" $out/conv.err | tail -2
$bin/prt-play $w/b.pool --backend cuda $cam --out $w/incore.ppm 2>$w/incore.err; echo "in core rc $?"; $bin/prt-accuracy compare $out/close.ppm $w/incore.ppm
for variant in "orbit" "orbit-noshadows --no-shadows"; do
  set -- $variant; name=$1; shift
  $bin/prt-play $w/b.pool --backend cuda --gpu-budget $budget $cam --frames 100 --orbit 1.0 --converge "$@" --out $w/$name.pfm 2>$out/$name.err
  echo "$name $*:"; python3 $here/orbit_summary.py $out/$name.err
done
$bin/prt-bench --backend cuda $w/b.pool --gpu-budget $budget $cam --frames 30 --warmup 5 --scenarios primary,shadow,reflect4 2>&1 | grep -vE "%|refining" | tail -6
gzip -f $out/orbit.err $out/orbit-noshadows.err
echo ALL_DONE
