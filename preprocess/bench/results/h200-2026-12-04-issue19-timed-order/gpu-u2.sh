#!/usr/bin/env bash
# Issue 17 / 19 (H200): the 500M room under an eighth of its pool with the queue order chosen by time
# (--kernel mega) against heavy items first (mega-heavy) and image order (mega-fifo): the close view's
# primary rays once resident, its first image, and the 100-frame orbit (t5 of
# ../h200-2026-12-04-issue17-coarse-prefix, before the megakernels were warmed at set_scene).
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/u2.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; t0=$SECONDS
rm -rf /tmp/ab; mkdir -p /tmp/ab; python3 -c "import tarfile; tarfile.open('build-ab/pack.tar.xz').extractall('/tmp/ab')"
bin=/tmp/ab/bin; w=/tmp/w500; mkdir -p $w
$bin/prt-synth room -n 500000000 -o $w/s.pool --quiet; $bin/prt-bricks $w/s.pool -o $w/b.pool --memory 12G --quiet; rm -f $w/s.pool
echo "pool done $((SECONDS - t0)) s"
cam="--eye 0.05,-0.2,0.2 --look-at -0.3,-0.6,-0.4 --up 0,1,0 --fov 50 --width 1024 --height 1024"
pool=$(stat -c %s $w/b.pool); budget=$(( pool / 8 ))
for k in mega mega-heavy mega-fifo; do
  echo "== $k (pool/8)"; $bin/prt-bench --backend cuda $w/b.pool --gpu-budget $budget $cam --frames 30 --warmup 5 --scenarios primary,shadow --kernel $k --json $w/b.json 2>&1 | grep -E "^(primary|shadow) +[0-9]"
  python3 -c "import json; print(' heavy-first frames:', [x['heavy_first_frames'] for x in json.load(open('$w/b.json'))['scenarios']])"
done
for k in mega mega-fifo; do
  s=$(date +%s.%N); $bin/prt-play $w/b.pool --backend cuda --kernel $k --gpu-budget $budget $cam --out $w/first.ppm 2>$w/first.err; echo "$k first image: $(python3 -c "print(round($(date +%s.%N) - $s, 2))") s; $(grep -E 'frame 0' $w/first.err | head -1 | cut -c1-60)"
  $bin/prt-play $w/b.pool --backend cuda --kernel $k --gpu-budget $budget $cam --frames 100 --orbit 1.0 --converge --out $w/orbit.ppm 2>$w/orbit-$k.err
  echo "$k orbit:"; python3 preprocess/bench/results/h200-2026-11-29-issue17-light/orbit_summary.py $w/orbit-$k.err
  grep -E "frame [0-9]+( pass [0-9]+)?: (4[5-9]|[5-9][0-9]|[0-9]{3})\.[0-9]+ ms" $w/orbit-$k.err | cut -c1-120
  gzip -c $w/orbit-$k.err > $out/orbit-500m-$k.err.gz
done
echo "ALL_DONE $((SECONDS - t0)) s"
