#!/usr/bin/env bash
# Issue 19 (H200): the landed candidate of heavy items first (factor 2, five classes). The GPU test
# programs, then prt-bench on the teapot and Bigguy (--kernel mega against mega-fifo, two rounds),
# then moving cameras: prt-play orbits (100 frames, 1 and 5 degrees a frame), GPU ms a frame.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/q4.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; t0=$SECONDS
rm -rf /tmp/ab; mkdir -p /tmp/ab
for p in pack10 pack23; do python3 -c "import tarfile; tarfile.open('build-ab/$p.tar.xz').extractall('/tmp/ab')"; done
n=/tmp/ab/p23; x=/tmp/ab/bin; cp -r /tmp/ab/p10 $x; cp $n/prt-bench $n/prt-play $x/; w=/tmp/q4; mkdir -p $w; q=--quiet
mkdir -p /work/shared/data/bezier && cp build-ab/bezier/* /work/shared/data/bezier/
mkdir -p /work/main/build-cu && ln -sfn "$x" /work/main/build-cu/bin
for t in $(ls $n | grep _gpu_tests); do
  PRT_BIN_DIR=$x timeout 300 $n/$t > $out/$t.log 2>&1; echo "$t rc $? $(grep -E '^\[  (PASSED|FAILED|SKIPPED)' $out/$t.log | tr '\n' ' ')"
done
grep -h -B2 -A6 "Failure" $out/*_gpu_tests.log | head -30; grep -h "SKIPPED \]" $out/*_gpu_tests.log | head
echo "tests done $((SECONDS - t0)) s"
$x/prt-patches build-ab/bezier/teapot.bpt -o $w/teapot.pool $q
$x/prt-patches build-ab/bezier/bigguy -o $w/bigguy.pool $q
bench() {  # bench LABEL ARGS...
  local label=$1; shift
  $x/prt-bench --backend cuda --frames 30 --warmup 5 --json $w/b.json "$@" > /dev/null 2> $w/err.txt \
    || { echo "$label failed: $(tail -2 $w/err.txt)"; return; }
  python3 - "$label" $w/b.json <<'PY'
import json, sys
j = json.load(open(sys.argv[2]))
print(sys.argv[1].ljust(24), ' '.join('%s %.3f (%d)' % (x['name'], x['grays_per_s'], x.get('heavy_first_items', -1)) for x in j['scenarios']), flush=True)
PY
}
for r in 1 2; do for k in mega-fifo mega; do
  bench "teapot $k" $w/teapot.pool --kernel $k --max-bounces 1 --scenarios primary,shadow,reflect4
  bench "bigguy $k" $w/bigguy.pool --kernel $k --max-bounces 1 --scenarios primary,shadow,reflect4
done; done
for k in mega-fifo mega; do bench "teapot 2048 $k" $w/teapot.pool --kernel $k --max-bounces 1 --scenarios primary,reflect4 --width 2048 --height 2048; done
$x/prt-bench --backend cuda --save-pool $w/room.pool --frames 1 --warmup 0 --scenarios primary $q > /dev/null 2>&1
for r in 1 2; do for d in 1 5; do for k in mega-fifo mega; do
  for m in teapot room; do
    extra="--max-bounces 1"; [ $m = room ] && extra="--scene preprocess/bench/bench_room.json"
    $x/prt-play $w/$m.pool --backend cuda --kernel $k $extra --width 1024 --height 1024 --frames 100 --orbit $d --out $w/o.ppm 2> $w/play.txt
    echo "orbit $m ${d} deg/frame $k: $(grep -oE 'GPU [0-9.]+ ms' $w/play.txt)"
  done
done; done; done
for k in mega-fifo mega; do $x/prt-play $w/teapot.pool --backend cuda --kernel $k --max-bounces 1 --width 1024 --height 1024 --frames 3 --out $w/t-$k.ppm $q; done
cmp $w/t-mega-fifo.ppm $w/t-mega.ppm && echo "teapot third frame: mega equals mega-fifo byte for byte"
echo "ALL_DONE $((SECONDS - t0)) s"
