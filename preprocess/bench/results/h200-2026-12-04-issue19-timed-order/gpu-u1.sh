#!/usr/bin/env bash
# Issue 19 (H200): the queue order chosen by time (--kernel mega: heavy items first or image order,
# rt::OrderChoice) against heavy items first in every frame (mega-heavy, 2026-12-03's default) and
# image order (mega-fifo). The GPU test programs; prt-bench on the rows heavy-first gained on
# (teapot, prt-bench's room, the culled room, the culled 10M sphere), still and turning 1 degree a
# frame; the first frame's render time with the megakernels warmed at set_scene.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/u1.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; t0=$SECONDS
rm -rf /tmp/ab; mkdir -p /tmp/ab
python3 -c "import tarfile; tarfile.open('build-ab/pack.tar.xz').extractall('/tmp/ab')"
x=/tmp/ab/bin; w=/tmp/u1; mkdir -p $w; q=--quiet
mkdir -p /work/shared/data/bezier && cp build-ab/bezier/* /work/shared/data/bezier/
mkdir -p /work/main/build-cu && ln -sfn "$x" /work/main/build-cu/bin
for t in $x/*_gpu_tests; do
  b=$(basename $t); PRT_BIN_DIR=$x timeout 240 $t > $w/$b.log 2>&1
  echo "$b rc $? $(grep -E '^\[  (PASSED|FAILED|SKIPPED)' $w/$b.log | tr '\n' ' ')"
  grep -B2 -A6 "Failure" $w/$b.log | head -20
done
tar -czf $out/gpu-test-logs.tar.gz -C $w $(cd $w && ls *_gpu_tests.log)
echo "tests done $((SECONDS - t0)) s"
$x/prt-patches build-ab/bezier/teapot.bpt -o $w/teapot.pool $q
$x/prt-bench --backend cuda --save-pool $w/room.pool --frames 1 --warmup 0 --scenarios primary $q > /dev/null 2>&1
$x/prt-cull $w/room.pool -o $w/culled.pool $q
$x/prt-synth sphere -n 10000000 -o $w/s10.pool $q && $x/prt-radii $w/s10.pool -o $w/s10.pool --backend cuda $q \
  && $x/prt-octree $w/s10.pool -o $w/s10.pool $q && $x/prt-cull $w/s10.pool -o $w/s10.pool $q || echo "sphere failed"
echo "pools done $((SECONDS - t0)) s"
bench() {  # bench LABEL ARGS...
  local label=$1; shift
  $x/prt-bench --backend cuda --frames 30 --warmup 5 --json $w/b.json "$@" > /dev/null 2> $w/err.txt \
    || { echo "$label failed: $(tail -2 $w/err.txt)"; return; }
  python3 - "$label" $w/b.json <<'PY'
import json, sys
j = json.load(open(sys.argv[2]))
print(sys.argv[1].ljust(30), ' '.join('%s %.3f (%d)' % (x['name'], x['grays_per_s'], x.get('heavy_first_frames', -1)) for x in j['scenarios']), flush=True)
PY
}
sph="--eye 0,0,3 --look-at 0,0,0 --up 0,1,0 --fov 45"; room="--scene preprocess/bench/bench_room.json"
for r in 1 2; do for k in mega-fifo mega-heavy mega; do
  bench "teapot $k" $w/teapot.pool --kernel $k --max-bounces 1 --scenarios primary,shadow,reflect4
  bench "default room $k" --kernel $k --scenarios primary,shadow,reflect4,full4
  bench "culled room $k" $w/culled.pool $room --kernel $k --scenarios primary,shadow,reflect4,full4
  bench "sphere10m $k" $w/s10.pool $sph --kernel $k --scenarios primary,shadow,reflect4
done; done
for k in mega-fifo mega-heavy mega; do
  bench "teapot orbit 1 $k" $w/teapot.pool --orbit 1 --frames 100 --kernel $k --max-bounces 1 --scenarios primary,shadow,reflect4
  bench "culled room orbit 1 $k" $w/culled.pool $room --orbit 1 --frames 100 --kernel $k --scenarios primary,shadow
done
echo "benches done $((SECONDS - t0)) s"
# the first frame: render ms of prt-play's frame 0 (megakernels now launched once at set_scene)
for k in mega-fifo mega; do
  $x/prt-play $w/culled.pool $room --backend cuda --kernel $k --width 1024 --height 1024 --out $w/f.ppm 2> $w/f.txt
  echo "first frame culled room $k: $(grep -E 'frame 0' $w/f.txt | head -1 | cut -c1-80)"
done
for k in mega-fifo mega-heavy mega; do $x/prt-play $w/teapot.pool --backend cuda --kernel $k --max-bounces 1 --width 1024 --height 1024 --frames 40 --out $w/t-$k.ppm $q; done
cmp $w/t-mega-fifo.ppm $w/t-mega.ppm && cmp $w/t-mega-heavy.ppm $w/t-mega.ppm && echo "teapot 40th frame: the three orders byte for byte equal"
echo "ALL_DONE $((SECONDS - t0)) s"
