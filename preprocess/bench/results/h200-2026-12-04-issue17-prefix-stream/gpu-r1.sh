#!/usr/bin/env bash
# Issue 17 (H200): streamed LOD prefixes (prefixes stream into the arena ahead of the payloads when
# the budget cannot hold them; a prefix's filled leaf is a LOD stop too). The GPU test programs of
# this tree, then the 100M room (prt-synth) bricked with --lod-splats 32 (default) and 12, streamed
# under --gpu-budget pool/8 at the two views of the README's row (inside; 3 units away),
# --converge, against the in-core image and the exact (--lod-pixels 0) one; the 100-frame orbit.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/r1.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; t0=$SECONDS
rm -rf /tmp/ab; mkdir -p /tmp/ab
for p in pack10 pack25; do python3 -c "import tarfile; tarfile.open('build-ab/$p.tar.xz').extractall('/tmp/ab')"; done
n=/tmp/ab/p25; cp -r /tmp/ab/p10 /tmp/ab/bin; cp $n/prt-play $n/prt-bench /tmp/ab/bin/; x=/tmp/ab/bin; w=/tmp/r1; mkdir -p $w; q=--quiet
mkdir -p /work/shared/data/bezier && cp build-ab/bezier/* /work/shared/data/bezier/
mkdir -p /work/main/build-cu && ln -sfn "$x" /work/main/build-cu/bin
for t in $n/*_gpu_tests; do
  b=$(basename $t); PRT_BIN_DIR=$x timeout 240 $t > $w/$b.log 2>&1
  echo "$b rc $? $(grep -E '^\[  (PASSED|FAILED|SKIPPED)' $w/$b.log | tr '\n' ' ')"
  grep -B2 -A6 "Failure" $w/$b.log | head -20
done
tar -czf $out/gpu-test-logs.tar.gz -C $w $(cd $w && ls *_gpu_tests.log)
echo "tests done $((SECONDS - t0)) s"
s=$SECONDS; $x/prt-synth room -n 100000000 -o $w/s.pool $q; echo "synth 100M: rc $? $((SECONDS - s)) s"
for m in 32 12; do
  s=$SECONDS; $x/prt-bricks $w/s.pool -o $w/b$m.pool --memory 12G --lod-splats $m $q; echo "bricks --lod-splats $m: rc $? $((SECONDS - s)) s, $(stat -c %s $w/b$m.pool) B"
done
rm -f $w/s.pool
pool=$(stat -c %s $w/b32.pool); budget=$(( pool / 8 )); echo "budget $budget B (the M=32 pool / 8)"
inside="--eye 0.55,0.1,0.75 --look-at 0,-0.4,0 --up 0,1,0 --fov 60 --width 1024 --height 1024"
outside="--eye 0.3,0.9,3.2 --look-at 0,-0.2,0 --up 0,1,0 --fov 50 --width 1024 --height 1024"
for m in 32 12; do for v in inside outside; do
  cam=${!v}
  s=$(date +%s.%N); timeout 120 $n/prt-play $w/b$m.pool --backend cuda --gpu-budget $budget $cam --converge --out $w/conv.ppm 2> $w/conv-$m-$v.err
  echo "M=$m $v: --converge rc $? $(python3 -c "print(round($(date +%s.%N) - $s, 2))") s wall; $(grep -E 'converge|pass\(es\)' $w/conv-$m-$v.err | tail -2 | tr '\n' ' ' | cut -c1-300)"
  grep -E "pass [0-9]+:" $w/conv-$m-$v.err | head -1 | cut -c1-330; grep -E "pass [0-9]+:" $w/conv-$m-$v.err | tail -1 | cut -c1-330
  $n/prt-play $w/b$m.pool --backend cuda $cam --out $w/incore.ppm $q
  [ $m = 32 ] && $n/prt-play $w/b$m.pool --backend cuda $cam --lod-pixels 0 --out $w/exact-$v.ppm $q
  echo "  streamed vs in core: $($x/prt-accuracy compare $w/conv.ppm $w/incore.ppm 2>&1 | tail -1 | cut -d: -f2-)"
  echo "  in core vs exact:    $($x/prt-accuracy compare $w/incore.ppm $w/exact-$v.ppm 2>&1 | tail -1 | cut -d: -f2-)"
  cp $w/conv.ppm $w/conv-$m-$v.ppm
done; done
for m in 32 12; do
  timeout 150 $n/prt-play $w/b$m.pool --backend cuda --gpu-budget $budget $inside --frames 100 --orbit 3.6 --converge --out $w/orbit.ppm 2> $w/orbit-$m.err
  echo "M=$m inside orbit, 3.6 degrees a frame, --converge: rc $?"; python3 preprocess/bench/results/h200-2026-11-29-issue17-light/orbit_summary.py $w/orbit-$m.err
done
python3 build-ab/ppm2png.py $w/conv-12-inside.ppm $out/conv-12-inside.png 2>/dev/null; python3 build-ab/ppm2png.py $w/conv-12-outside.ppm $out/conv-12-outside.png 2>/dev/null
tar -czf $out/errs.tar.gz -C $w $(cd $w && ls *.err)
echo "ALL_DONE $((SECONDS - t0)) s"
