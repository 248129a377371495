#!/usr/bin/env bash
# Issue 17 (H200): the level-of-detail row measured again on today's tree (it dates from 2026-11-25,
# bricks of 32768 then): the 100M-point room built from points (prt-bricks computes the radii on
# the GPU, --memory 12G), streamed under --gpu-budget pool/8 at the two views of that row (inside
# the room; 3 units away), --lod-pixels 1 (default): converged or not, against the in-core image,
# then the 100-frame orbit of the inside view (3.6 degrees a frame, --converge).
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/q7.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; t0=$SECONDS
rm -rf /tmp/ab; mkdir -p /tmp/ab
for p in pack10 pack23; do python3 -c "import tarfile; tarfile.open('build-ab/$p.tar.xz').extractall('/tmp/ab')"; done
n=/tmp/ab/p23; x=/tmp/ab/p10; w=/tmp/q7; mkdir -p $w; q=--quiet
s=$SECONDS; $x/prt-synth room -n 100000000 -o $w/s.pool $q; echo "synth 100M: rc $? $((SECONDS - s)) s"
s=$SECONDS; $x/prt-bricks $w/s.pool -o $w/b.pool --memory 12G $q; echo "bricks: rc $? $((SECONDS - s)) s"; rm -f $w/s.pool
pool=$(stat -c %s $w/b.pool); budget=$(( pool / 8 )); echo "pool $pool B, budget $budget B (pool / 8)"
inside="--eye 0.55,0.1,0.75 --look-at 0,-0.4,0 --up 0,1,0 --fov 60 --width 1024 --height 1024"
outside="--eye 0.3,0.9,3.2 --look-at 0,-0.2,0 --up 0,1,0 --fov 50 --width 1024 --height 1024"
for v in inside outside; do
  cam=${!v}
  s=$(date +%s.%N); timeout 120 $n/prt-play $w/b.pool --backend cuda --gpu-budget $budget $cam --converge --out $w/conv-$v.ppm 2> $w/conv-$v.err
  echo "$v: --converge rc $? $(python3 -c "print(round($(date +%s.%N) - $s, 2))") s wall"; grep -E "converge|pass\(es\)" $w/conv-$v.err | tail -2 | cut -c1-300
  grep -E "frame 0 pass" $w/conv-$v.err | tail -1 | cut -c1-300
  $n/prt-play $w/b.pool --backend cuda $cam --out $w/incore-$v.ppm $q; $x/prt-accuracy compare $w/conv-$v.ppm $w/incore-$v.ppm 2>&1 | tail -2
done
timeout 200 $n/prt-play $w/b.pool --backend cuda --gpu-budget $budget $inside --frames 100 --orbit 3.6 --converge --out $w/orbit.ppm 2> $w/orbit.err
echo "inside orbit, 3.6 degrees a frame, --converge: rc $?"; python3 preprocess/bench/results/h200-2026-11-29-issue17-light/orbit_summary.py $w/orbit.err
gzip -c $w/orbit.err > $out/orbit.err.gz; cp $w/conv-*.err $out/
echo "ALL_DONE $((SECONDS - t0)) s"
