#!/usr/bin/env bash
# Issue 19 (H200): why the timed order (mega) ran the culled room's shadow and full4 scenarios 5 %
# slower than mega-heavy in u1/u3's four-scenario runs though it chose heavy items first in every
# timed frame, while full4 alone ran the same: every scenario's frames one by one, both modes, and
# the scenarios in another order.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/u4.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm --format=csv,noheader; t0=$SECONDS
rm -rf /tmp/ab; mkdir -p /tmp/ab
python3 -c "import tarfile; tarfile.open('build-ab/pack.tar.xz').extractall('/tmp/ab')"
x=/tmp/ab/bin; w=/tmp/u4; mkdir -p $w; q=--quiet
$x/prt-bench --backend cuda --save-pool $w/room.pool --frames 1 --warmup 0 --scenarios primary $q > /dev/null 2>&1
$x/prt-cull $w/room.pool -o $w/culled.pool $q
room="--scene preprocess/bench/bench_room.json"
for r in 1 2; do for sc in primary,shadow,reflect4,full4 full4,shadow,primary; do for k in mega-heavy mega; do
  $x/prt-bench --backend cuda --frames 30 --warmup 5 --json $w/b.json $w/culled.pool $room --kernel $k --scenarios $sc > /dev/null 2>&1
  echo "== $k $sc"
  python3 -c "
import json
for s in json.load(open('$w/b.json'))['scenarios']:
    print(' %-9s %.3f ms' % (s['name'], s['grays_per_s']), ' '.join('%.2f' % v for v in s['frames_ms'][:12]), '| heavy', s['frames_heavy_first_items'][:6])"
done; done; done
echo "ALL_DONE $((SECONDS - t0)) s"
