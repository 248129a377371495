#!/usr/bin/env bash
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/s7.txt") 2>&1
bin=$PWD/build-cuda/bin; w=/tmp/ws; mkdir -p $w
[ -f $w/b.pool ] || { $bin/prt-synth room -n 500000000 -o $w/s.pool --quiet; echo "synth rc $?"; $bin/prt-bricks $w/s.pool -o $w/b.pool --memory 12G --quiet; echo "bricks rc $?"; rm -f $w/s.pool; }
cam="--eye 0.05,-0.2,0.2 --look-at -0.3,-0.6,-0.4 --up 0,1,0 --fov 50 --width 1024 --height 1024"
pool=$(stat -c %s $w/b.pool); budget=$(( pool / 8 ))
$bin/prt-play $w/b.pool --backend cuda --gpu-budget $budget $cam --frames 100 --orbit 1.0 --converge --out $w/orbit.pfm 2>$out/orbit.err
echo "orbit, --frame-time 50 (default):"; python3 "$(dirname "$0")/orbit_summary.py" $out/orbit.err
grep -E "frame [0-9]+( pass [0-9]+)?: (4[5-9]|[5-9][0-9]|[0-9]{3})\.[0-9]+ ms" $out/orbit.err | cut -c1-200
gzip -f $out/orbit.err
echo ALL_DONE
