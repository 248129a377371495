#!/usr/bin/env bash
# Issue 17 (H200): streamed LOD prefixes in two steps (coarse part, then whole). The GPU test
# programs; in-core bricks against the float octree (culled 1M room, bench_room.json); the 100M room
# (--lod-splats 32 and 12) streamed under pool/8 (inside view, its 100-frame orbit) and the outside
# view under pool/8, pool/4 and pool/2, --converge (compare with ../h200-2026-12-04-issue17-prefix-stream/r7.txt,
# the same pools and views before this change).
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/t1.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; t0=$SECONDS
rm -rf /tmp/ab; mkdir -p /tmp/ab
python3 -c "import tarfile; tarfile.open('build-ab/pack.tar.xz').extractall('/tmp/ab')"
x=/tmp/ab/bin; w=/tmp/t1; mkdir -p $w; q=--quiet
mkdir -p /work/shared/data/bezier && cp build-ab/bezier/* /work/shared/data/bezier/
mkdir -p /work/main/build-cu && ln -sfn "$x" /work/main/build-cu/bin
for t in $x/*_gpu_tests; do
  b=$(basename $t); PRT_BIN_DIR=$x timeout 240 $t > $w/$b.log 2>&1
  echo "$b rc $? $(grep -E '^\[  (PASSED|FAILED|SKIPPED)' $w/$b.log | tr '\n' ' ')"
  grep -B2 -A6 "Failure" $w/$b.log | head -20
done
tar -czf $out/gpu-test-logs.tar.gz -C $w $(cd $w && ls *_gpu_tests.log)
bench() {  # bench LABEL ARGS...
  local label=$1; shift
  $x/prt-bench --backend cuda --frames 40 --warmup 5 --json $w/b.json "$@" > /dev/null 2> $w/err.txt \
    || { echo "$label failed: $(tail -2 $w/err.txt)"; return; }
  python3 - "$label" $w/b.json <<'PY'
import json, sys
j = json.load(open(sys.argv[2]))
print(sys.argv[1].ljust(28), ' '.join('%s %.3f' % (x['name'], x['grays_per_s']) for x in j['scenarios']), flush=True)
PY
}
$x/prt-bench --backend cuda --save-pool $w/room.pool --frames 1 --warmup 0 --scenarios primary $q > /dev/null 2>&1
$x/prt-cull $w/room.pool -o $w/culled.pool $q; $x/prt-bricks $w/culled.pool -o $w/cb.pool $q
for r in 1 2; do
  bench "float lod 1" $w/culled.pool --scene preprocess/bench/bench_room.json --scenarios primary,shadow,full4 --lod-pixels 1
  bench "bricks lod 1" $w/cb.pool --scene preprocess/bench/bench_room.json --scenarios primary,shadow,full4 --lod-pixels 1
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
tar -czf $out/errs.tar.gz -C $w $(cd $w && ls *.err)
echo "ALL_DONE $((SECONDS - t0)) s"
