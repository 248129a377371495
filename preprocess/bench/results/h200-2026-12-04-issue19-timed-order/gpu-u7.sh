#!/usr/bin/env bash
# Issues 17 / 19 (H200): the landed tree (heavy items first in every frame, --kernel mega, the
# default; the megakernels warmed at set_scene; no timed order): every GPU test program, then the
# 500M room under an eighth of its pool: the close view's primary and shadow rays once resident
# (Grays/s from prt-bench's JSON), its first image, and the 100-frame orbit with --converge.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/u7.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; t0=$SECONDS
rm -rf /tmp/ab; mkdir -p /tmp/ab; python3 -c "import tarfile; tarfile.open('build-ab/pack.tar.xz').extractall('/tmp/ab')"
x=/tmp/ab/bin; bin=$x; w=/tmp/w500; mkdir -p $w /tmp/u7
mkdir -p /work/shared/data/bezier && cp build-ab/bezier/* /work/shared/data/bezier/
mkdir -p /work/main/build-cu && ln -sfn "$x" /work/main/build-cu/bin
for t in $x/*_gpu_tests; do
  b=$(basename $t); PRT_BIN_DIR=$x timeout 240 $t > /tmp/u7/$b.log 2>&1
  echo "$b rc $? $(grep -E '^\[  (PASSED|FAILED|SKIPPED)' /tmp/u7/$b.log | tr '\n' ' ')"
  grep -B2 -A6 "Failure" /tmp/u7/$b.log | head -20
done
tar -czf $out/gpu-test-logs.tar.gz -C /tmp/u7 $(cd /tmp/u7 && ls *_gpu_tests.log)
echo "tests done $((SECONDS - t0)) s"
[ -s $w/b.pool ] || { $bin/prt-synth room -n 500000000 -o $w/s.pool --quiet; $bin/prt-bricks $w/s.pool -o $w/b.pool --memory 12G --quiet; rm -f $w/s.pool; }
echo "pool done $((SECONDS - t0)) s"
cam="--eye 0.05,-0.2,0.2 --look-at -0.3,-0.6,-0.4 --up 0,1,0 --fov 50 --width 1024 --height 1024"
pool=$(stat -c %s $w/b.pool); budget=$(( pool / 8 ))
for k in mega mega-fifo; do
  $bin/prt-bench --backend cuda $w/b.pool --gpu-budget $budget $cam --frames 30 --warmup 5 --scenarios primary,shadow --kernel $k --json $w/b.json > /dev/null 2>&1
  python3 -c "
import json
for s in json.load(open('$w/b.json'))['scenarios']: print('close view $k %-8s %.3f Grays/s, median %.3f ms, heavy-first frames %d' % (s['name'], s['grays_per_s'], s['median_ms'], s['heavy_first_frames']))"
done
s=$(date +%s.%N); $bin/prt-play $w/b.pool --backend cuda --gpu-budget $budget $cam --out $w/first.ppm 2>$w/first.err; echo "first image: $(python3 -c "print(round($(date +%s.%N) - $s, 2))") s; $(grep -E 'frame 0' $w/first.err | head -1 | cut -c1-60)"
$bin/prt-play $w/b.pool --backend cuda --gpu-budget $budget $cam --frames 100 --orbit 1.0 --converge --out $w/orbit.ppm 2>$w/orbit.err
echo "orbit:"; python3 preprocess/bench/results/h200-2026-11-29-issue17-light/orbit_summary.py $w/orbit.err
grep -E "frame [0-9]+( pass [0-9]+)?: (4[5-9]|[5-9][0-9]|[0-9]{3})\.[0-9]+ ms" $w/orbit.err | cut -c1-120
gzip -c $w/orbit.err > $out/orbit-500m-u7.err.gz
echo "ALL_DONE $((SECONDS - t0)) s"
