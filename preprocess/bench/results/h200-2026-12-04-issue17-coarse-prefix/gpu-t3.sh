#!/usr/bin/env bash
# Issue 17 (H200): t1 and t2 again after the residency rule changed (prefixes resident when they take
# at most half of the arena and prefixes, a quarter before): the brick-stream GPU tests, the 100M
# room's streamed views and orbit (t1's), the 500M room under pool/8 (t2's).
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/t3.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; t0=$SECONDS
rm -rf /tmp/ab; mkdir -p /tmp/ab
python3 -c "import tarfile; tarfile.open('build-ab/pack.tar.xz').extractall('/tmp/ab')"
x=/tmp/ab/bin; bin=$x; w=/tmp/t1; mkdir -p $w; q=--quiet
mkdir -p /work/shared/data/bezier && cp build-ab/bezier/* /work/shared/data/bezier/
mkdir -p /work/main/build-cu && ln -sfn "$x" /work/main/build-cu/bin
for t in $x/prt_brick_stream_gpu_tests $x/prt_runtime_gpu_tests; do
  b=$(basename $t); PRT_BIN_DIR=$x timeout 240 $t > $w/$b.log 2>&1
  echo "$b rc $? $(grep -E '^\[  (PASSED|FAILED|SKIPPED)' $w/$b.log | tr '\n' ' ')"
done
s=$SECONDS; $x/prt-synth room -n 100000000 -o $w/s.pool $q; echo "synth 100M: rc $? $((SECONDS - s)) s"
for m in 32 12; do $x/prt-bricks $w/s.pool -o $w/b$m.pool --memory 12G --lod-splats $m $q; done; rm -f $w/s.pool
pool=$(stat -c %s $w/b32.pool); echo "pools $pool / $(stat -c %s $w/b12.pool) B"
inside="--eye 0.55,0.1,0.75 --look-at 0,-0.4,0 --up 0,1,0 --fov 60 --width 1024 --height 1024"
outside="--eye 0.3,0.9,3.2 --look-at 0,-0.2,0 --up 0,1,0 --fov 50 --width 1024 --height 1024"
conv() {  # conv M VIEW DIVISOR
  local cam=${!2} budget=$(( pool / $3 ))
  s=$(date +%s.%N); timeout 100 $x/prt-play $w/b$1.pool --backend cuda --gpu-budget $budget $cam --converge --out $w/conv.ppm 2> $w/conv-$1-$2-$3.err
  echo "M=$1 $2 pool/$3: rc $? $(python3 -c "print(round($(date +%s.%N) - $s, 2))") s wall; $(grep -E 'converge|pass\(es\)' $w/conv-$1-$2-$3.err | tail -2 | tr '\n' ' ' | cut -c1-260)"
  grep -E "pass [0-9]+:" $w/conv-$1-$2-$3.err | tail -1 | cut -c1-400
  $x/prt-play $w/b$1.pool --backend cuda $cam --out $w/incore.ppm $q
  echo "  streamed vs in core: $($x/prt-accuracy compare $w/conv.ppm $w/incore.ppm 2>&1 | tail -1 | cut -d: -f2-)"
}
for m in 32 12; do conv $m inside 8; done
for d in 8 4 2; do for m in 32 12; do conv $m outside $d; done; done
for m in 32 12; do
  timeout 150 $x/prt-play $w/b$m.pool --backend cuda --gpu-budget $(( pool / 8 )) $inside --frames 100 --orbit 3.6 --converge --out $w/orbit.ppm 2> $w/orbit-$m.err
  echo "M=$m inside orbit, 3.6 degrees a frame, --converge: rc $?"; python3 preprocess/bench/results/h200-2026-11-29-issue17-light/orbit_summary.py $w/orbit-$m.err
done
tar -czf $out/errs100.tar.gz -C $w $(cd $w && ls *.err); rm -f $w/b*.pool
w=/tmp/w500; mkdir -p $w
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
