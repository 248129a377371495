#!/usr/bin/env bash
# Issue 17 (H200): the 500M room under an eighth of its pool with this tree (streamed prefixes since
# a7f4b0f's parent, coarse parts first since 9cc9fe1): first image, the close view converged, primary
# and shadow once resident, the 100-frame orbit (1 degree a frame, --converge, --frame-time 50).
# Same pool, view and orbit as ../h200-2026-11-29-issue17-bounds16/gpu-b2.sh.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/t2.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; t0=$SECONDS
rm -rf /tmp/ab; mkdir -p /tmp/ab; python3 -c "import tarfile; tarfile.open('build-ab/pack.tar.xz').extractall('/tmp/ab')"
bin=/tmp/ab/bin; w=/tmp/w500; mkdir -p $w
s=$SECONDS; $bin/prt-synth room -n 500000000 -o $w/s.pool --quiet; echo "synth 500M: rc $? $((SECONDS - s)) s"
s=$SECONDS; /usr/bin/time -f "%e s wall, %U s user, %S s sys, peak RSS %M KB" $bin/prt-bricks $w/s.pool -o $w/b.pool --memory 12G --quiet --stats-json $out/bricks500.json; echo "bricks: rc $? $((SECONDS - s)) s"
rm -f $w/s.pool
cam="--eye 0.05,-0.2,0.2 --look-at -0.3,-0.6,-0.4 --up 0,1,0 --fov 50 --width 1024 --height 1024"
pool=$(stat -c %s $w/b.pool); budget=$(( pool / 8 )); echo "pool $pool B, budget $budget B (pool / 8)"
s=$(date +%s.%N); $bin/prt-play $w/b.pool --backend cuda --gpu-budget $budget $cam --out $w/first.ppm 2>$w/first.err; echo "first image (one pass): $(python3 -c "print(round($(date +%s.%N) - $s, 2))") s wall from process start"; grep -E "frame 0" $w/first.err | head -2 | cut -c1-400
s=$(date +%s.%N); $bin/prt-play $w/b.pool --backend cuda --gpu-budget $budget $cam --converge --out $w/conv.ppm 2>$out/conv.err; echo "close view converged: $(python3 -c "print(round($(date +%s.%N) - $s, 2))") s wall"; grep -E "pass\(es\)|converge" $out/conv.err | tail -2 | cut -c1-300; grep -E "pass [0-9]+:" $out/conv.err | tail -1 | cut -c1-400
$bin/prt-play $w/b.pool --backend cuda $cam --out $w/incore.ppm --quiet
echo "  streamed vs in core: $($bin/prt-accuracy compare $w/conv.ppm $w/incore.ppm 2>&1 | tail -1 | cut -d: -f2-)"
$bin/prt-bench --backend cuda $w/b.pool --gpu-budget $budget $cam --frames 30 --warmup 5 --scenarios primary,shadow 2>&1 | grep -vE "%|refining" | tail -5
$bin/prt-play $w/b.pool --backend cuda --gpu-budget $budget $cam --frames 100 --orbit 1.0 --converge --out $w/orbit.ppm 2>$out/orbit.err
echo "orbit, --frame-time 50 (default):"; python3 preprocess/bench/results/h200-2026-11-29-issue17-light/orbit_summary.py $out/orbit.err
grep -E "frame [0-9]+( pass [0-9]+)?: (4[5-9]|[5-9][0-9]|[0-9]{3})\.[0-9]+ ms" $out/orbit.err | cut -c1-300
grep -c "LOD prefixes" $out/orbit.err; gzip -f $out/orbit.err
echo "ALL_DONE $((SECONDS - t0)) s"
