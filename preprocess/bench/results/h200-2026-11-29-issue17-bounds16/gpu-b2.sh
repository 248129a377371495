#!/usr/bin/env bash
# Issue 17 on the GPU host (16 cores, one H200): the 500M room under an eighth of its pool with brick
# leaf bounds in 16 bytes: first image, the close view converged against the in-core image, the
# 100-frame orbit (1 degree a frame, --converge, --frame-time 50 by default). Same pool, views and
# orbit as ../h200-2026-11-29-issue17-light/gpu-s6.sh.
# Usage (repository root): BIN=build-cuda/bin bash .../gpu-b2.sh
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/b2.txt") 2>&1
bin=$(cd "$BIN" && pwd); w=/tmp/w500; mkdir -p $w; here=$(dirname "$0")
if [ ! -s $w/b.pool ]; then
  s=$SECONDS; $bin/prt-synth room -n 500000000 -o $w/s.pool --quiet; echo "synth 500M: rc $? $((SECONDS - s)) s"
  s=$SECONDS; $bin/prt-bricks $w/s.pool -o $w/b.pool --memory 12G --quiet; echo "bricks: rc $? $((SECONDS - s)) s"
  rm -f $w/s.pool
fi
cam="--eye 0.05,-0.2,0.2 --look-at -0.3,-0.6,-0.4 --up 0,1,0 --fov 50 --width 1024 --height 1024"
pool=$(stat -c %s $w/b.pool); budget=$(( pool / 8 )); echo "pool $pool B, budget $budget B (pool / 8)"
s=$(date +%s.%N); $bin/prt-play $w/b.pool --backend cuda --gpu-budget $budget $cam --out $w/first.pfm 2>$w/first.err; echo "first image (one pass): $(python3 -c "print(round($(date +%s.%N) - $s, 2))") s wall from process start"; grep -E "frame 0" $w/first.err | head -2 | cut -c1-300
s=$(date +%s.%N); $bin/prt-play $w/b.pool --backend cuda --gpu-budget $budget $cam --converge --out $w/conv.ppm 2>$out/conv.err; echo "close view converged: $(python3 -c "print(round($(date +%s.%N) - $s, 2))") s wall"; grep -E "pass\(es\)|converge" $out/conv.err | tail -2 | cut -c1-300
$bin/prt-play $w/b.pool --backend cuda $cam --out $w/incore.ppm 2>/dev/null; $bin/prt-accuracy compare $w/conv.ppm $w/incore.ppm
$bin/prt-bench --backend cuda $w/b.pool --gpu-budget $budget $cam --frames 30 --warmup 5 --scenarios primary,shadow 2>&1 | grep -vE "%|refining" | tail -5
$bin/prt-play $w/b.pool --backend cuda --gpu-budget $budget $cam --frames 100 --orbit 1.0 --converge --out $w/orbit.pfm 2>$out/orbit.err
echo "orbit, --frame-time 50 (default):"; python3 $here/../h200-2026-11-29-issue17-light/orbit_summary.py $out/orbit.err
grep -E "frame [0-9]+( pass [0-9]+)?: (4[5-9]|[5-9][0-9]|[0-9]{3})\.[0-9]+ ms" $out/orbit.err | cut -c1-200
gzip -f $out/orbit.err
echo ALL_DONE
