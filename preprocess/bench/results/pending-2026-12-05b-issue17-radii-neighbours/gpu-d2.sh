#!/usr/bin/env bash
# Issue 17, pending (written 2026-12-05, no device lent): cell workers that sleep while they wait for
# the GPU (blocking-waits.patch: cudaDeviceScheduleBlockingSync when prt-bricks builds cells on the
# GPU with several workers), so that more workers than cores can fill the cores with the cells' CPU
# work. Carried: build-ab/pack.tar.xz (main, folder bin/) and build-ab/blk.tar.xz (folder blk/:
# prt-bricks built with the patch applied to the same main). The 500M room from points
# (--memory 12G, 16 cores): main, blk, blk with 24 and 32 cell workers, and main with glibc's malloc
# keeping freed blocks below 32 MiB in its arenas (tun16: does the cells' allocation churn, fresh
# zeroed pages for every cell, cost the host's 57 s of system time?); sections compared, pools
# removed as it goes.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/d2.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader; t0=$SECONDS; root=$PWD
rm -rf /tmp/ab; mkdir -p /tmp/ab
python3 -c "import tarfile; tarfile.open('build-ab/pack.tar.xz').extractall('/tmp/ab'); tarfile.open('build-ab/blk.tar.xz').extractall('/tmp/ab')"
x=/tmp/ab/bin; blk=/tmp/ab/blk; w=/tmp/wd2; mkdir -p $w
$x/prt-synth room -n 500000000 -o $w/s.pool --quiet
echo "synth done $((SECONDS - t0)) s"
line() {  # label binary [options]
  /usr/bin/time -f "%e s wall, %U s user, %S s sys, peak RSS %M KB" $2 $w/s.pool -o $w/b-$1.pool --memory 12G --quiet ${3:-} \
    --stats-json $out/bricks500-$1.json 2>$w/time.txt; echo -n "$1: $(tail -1 $w/time.txt) "
  python3 -c "
import json, os; s = json.load(open('$out/bricks500-$1.json'))
print(' total %.1f s, build %.1f s, %.2fM pts/s; summed: octree %.1f bricks %.1f payload writes %s partition %.1f assemble %.1f; %.2f B/point' % (s['total_seconds'], s['build_seconds'], s['points_per_second'] / 1e6, s['seconds']['octree'], s['seconds']['bricks'], s['seconds'].get('payload_writes'), s['seconds']['partition'], s['seconds']['assemble'], os.path.getsize('$w/b-$1.pool') / 5e8))
print('   radii', s['radii'], 'partition passes', s.get('partition_passes'), 'peak RSS', s['peak_rss_bytes'])"
}
sum() {  # label: the pool's sections summarised, then the pool removed (the disk holds 64 GiB)
  python3 $root/preprocess/bench/results/h200-2026-12-04-issue17-cells-alloc/poolsum.py $w/b-$1.pool > $w/$1.sum; rm -f $w/b-$1.pool
}
line main1 $x/prt-bricks; sum main1
line blk16 $blk/prt-bricks; sum blk16
line blk24 $blk/prt-bricks "--cell-workers 24"; sum blk24
line blk32 $blk/prt-bricks "--cell-workers 32"; sum blk32
export GLIBC_TUNABLES=glibc.malloc.mmap_threshold=33554432:glibc.malloc.trim_threshold=4294967296
line tun16 $x/prt-bricks; unset GLIBC_TUNABLES; sum tun16
for v in blk16 blk24 blk32 tun16; do
  cmp -s $w/main1.sum $w/$v.sum && echo "500M bricks $v: sections equal to main1" || echo "500M bricks $v: SECTIONS DIFFER"
done
echo "ALL_DONE $((SECONDS - t0)) s"
