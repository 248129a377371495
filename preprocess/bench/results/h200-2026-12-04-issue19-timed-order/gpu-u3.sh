#!/usr/bin/env bash
# Issue 19 (H200): u1 again after its fixes (the choice measured only once the queue has lists to
# use, two warm frames a key; prt-bench's JSON with per-frame ms): the timed order (--kernel mega)
# against heavy items first (mega-heavy) and image order (mega-fifo) on u1's rows, still and
# turning 1 degree a frame; the culled room's full4 frames one by one.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/u3.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; t0=$SECONDS
rm -rf /tmp/ab; mkdir -p /tmp/ab
python3 -c "import tarfile; tarfile.open('build-ab/pack.tar.xz').extractall('/tmp/ab')"
x=/tmp/ab/bin; w=/tmp/u3; mkdir -p $w; q=--quiet
mkdir -p /work/shared/data/bezier && cp build-ab/bezier/* /work/shared/data/bezier/
mkdir -p /work/main/build-cu && ln -sfn "$x" /work/main/build-cu/bin
PRT_BIN_DIR=$x timeout 240 $x/prt_runtime_gpu_tests > $w/rt.log 2>&1; echo "prt_runtime_gpu_tests rc $? $(grep -E '^\[  (PASSED|FAILED)' $w/rt.log | tr '\n' ' ')"
$x/prt-patches build-ab/bezier/teapot.bpt -o $w/teapot.pool $q
$x/prt-bench --backend cuda --save-pool $w/room.pool --frames 1 --warmup 0 --scenarios primary $q > /dev/null 2>&1
$x/prt-cull $w/room.pool -o $w/culled.pool $q
$x/prt-synth sphere -n 10000000 -o $w/s10.pool $q && $x/prt-radii $w/s10.pool -o $w/s10.pool --backend cuda $q \
  && $x/prt-octree $w/s10.pool -o $w/s10.pool $q && $x/prt-cull $w/s10.pool -o $w/s10.pool $q || echo "sphere failed"
echo "pools done $((SECONDS - t0)) s"
bench() {  # bench LABEL FRAMES ARGS...
  local label=$1 frames=$2; shift 2
  $x/prt-bench --backend cuda --frames $frames --warmup 5 --json $w/b.json "$@" > /dev/null 2> $w/err.txt \
    || { echo "$label failed: $(tail -2 $w/err.txt)"; return; }
  python3 - "$label" $w/b.json <<'PY'
import json, sys
j = json.load(open(sys.argv[2]))
print(sys.argv[1].ljust(30), ' '.join('%s %.3f (%d)' % (x['name'], x['grays_per_s'], x.get('heavy_first_frames', -1)) for x in j['scenarios']), flush=True)
PY
}
sph="--eye 0,0,3 --look-at 0,0,0 --up 0,1,0 --fov 45"; room="--scene preprocess/bench/bench_room.json"
for r in 1 2; do for k in mega-fifo mega-heavy mega; do
  bench "teapot $k" 30 $w/teapot.pool --kernel $k --max-bounces 1 --scenarios primary,shadow,reflect4
  bench "default room $k" 30 --kernel $k --scenarios primary,shadow,reflect4,full4
  bench "culled room $k" 30 $w/culled.pool $room --kernel $k --scenarios primary,shadow,reflect4,full4
  bench "sphere10m $k" 30 $w/s10.pool $sph --kernel $k --scenarios primary,shadow,reflect4
done; done
for k in mega-heavy mega; do
  bench "culled room full4 $k" 30 $w/culled.pool $room --kernel $k --scenarios full4
  python3 -c "import json; s=json.load(open('$w/b.json'))['scenarios'][0]; print(' ms', ' '.join('%.3f' % v for v in s['frames_ms'])); print(' heavy', s['frames_heavy_first_items'])"
done
for k in mega-fifo mega-heavy mega; do
  bench "teapot orbit 1 $k" 100 $w/teapot.pool --orbit 1 --kernel $k --max-bounces 1 --scenarios primary,shadow,reflect4
  bench "culled room orbit 1 $k" 100 $w/culled.pool $room --orbit 1 --kernel $k --scenarios primary,shadow
done
echo "ALL_DONE $((SECONDS - t0)) s"
