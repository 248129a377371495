#!/usr/bin/env bash
# Issue 17: the 500M room's orbit under an eighth of its pool with --frame-time (default 50 ms):
# uploads after a frame stop once the frame has taken 50 ms. Then the streaming GPU tests.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/s6.txt") 2>&1
bin=$PWD/build-cuda/bin; w=/tmp/ws; mkdir -p $w; rm -f $w/*.pool
build-cuda/pack/prt_brick_stream_gpu_tests 2>&1 | tail -3
s=$SECONDS; $bin/prt-synth room -n 500000000 -o $w/s.pool --quiet; echo "synth 500M: rc $? $((SECONDS - s)) s"
s=$SECONDS; $bin/prt-bricks $w/s.pool -o $w/b.pool --memory 12G --quiet; echo "bricks: rc $? $((SECONDS - s)) s"
rm -f $w/s.pool
cam="--eye 0.05,-0.2,0.2 --look-at -0.3,-0.6,-0.4 --up 0,1,0 --fov 50 --width 1024 --height 1024"
pool=$(stat -c %s $w/b.pool); budget=$(( pool / 8 )); echo "pool $pool B, budget $budget B (pool / 8)"
s=$(date +%s.%N); $bin/prt-play $w/b.pool --backend cuda --gpu-budget $budget $cam --out $w/first.pfm 2>$w/first.err; echo "first image (one pass): $(python3 -c "print(round($(date +%s.%N) - $s, 2))") s wall from process start"; grep -E "frame 0" $w/first.err | head -2
s=$(date +%s.%N); $bin/prt-play $w/b.pool --backend cuda --gpu-budget $budget $cam --converge --out $w/conv.ppm 2>$out/conv.err; echo "close view converged: $(python3 -c "print(round($(date +%s.%N) - $s, 2))") s wall"; grep -E "pass\(es\)|converge" $out/conv.err | tail -2
$bin/prt-play $w/b.pool --backend cuda $cam --out $w/incore.ppm 2>/dev/null; $bin/prt-accuracy compare $w/conv.ppm $w/incore.ppm
$bin/prt-play $w/b.pool --backend cuda --gpu-budget $budget $cam --frames 100 --orbit 1.0 --converge --out $w/orbit.pfm 2>$out/orbit.err
echo "orbit, --frame-time 50 (default):"; python3 "$(dirname "$0")/orbit_summary.py" $out/orbit.err
gzip -f $out/orbit.err
echo ALL_DONE
