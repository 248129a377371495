#!/usr/bin/env bash
# Issue 17, 2026-12-05: the partition's scatter taking each single-cell point's cell from the count
# pass (40aee96) against the tree before it (d3b5a1e, build-ab/cur.tar.xz), both built on the dev VM
# and carried: the 500M room from points (prt-synth's pool straight into prt-bricks, --memory 12G,
# 16 cores), new / cur / new, then new with 24 and 32 cell workers (one per core by default: does
# a worker waiting for the GPU leave its core idle?), pool sections compared.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/c2.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; t0=$SECONDS; root=$PWD
rm -rf /tmp/ab; mkdir -p /tmp/ab
python3 -c "import tarfile; tarfile.open('build-ab/pack.tar.xz').extractall('/tmp/ab'); tarfile.open('build-ab/cur.tar.xz').extractall('/tmp/ab')"
x=/tmp/ab/bin; cur=/tmp/ab/cur; w=/tmp/wc2; mkdir -p $w
$x/prt-synth room -n 500000000 -o $w/s.pool --quiet
echo "synth done $((SECONDS - t0)) s"
line() {  # label binary [options]
  /usr/bin/time -f "%e s wall, %U s user, %S s sys, peak RSS %M KB" $2 $w/s.pool -o $w/b-$1.pool --memory 12G --quiet ${3:-} \
    --stats-json $out/bricks500-$1.json 2>$w/time.txt; echo -n "$1: $(tail -1 $w/time.txt) "
  python3 -c "
import json, os; s = json.load(open('$out/bricks500-$1.json'))
print(' total %.1f s, build %.1f s, %.2fM pts/s; summed: octree %.1f cull %.1f bricks %.1f partition %.1f assemble %.1f; %.2f B/point' % (s['total_seconds'], s['build_seconds'], s['points_per_second'] / 1e6, s['seconds']['octree'], s['seconds']['cull'], s['seconds']['bricks'], s['seconds']['partition'], s['seconds']['assemble'], os.path.getsize('$w/b-$1.pool') / 5e8))
print('   cells', s['cells'], 'on device', s.get('cells_culled_on_device'), 'partition passes', s.get('partition_passes'), 'radii', s['radii'], 'peak RSS', s['peak_rss_bytes'])"
}
sum() {  # label: the pool's sections summarised, then the pool removed (the disk holds 64 GiB)
  python3 $root/preprocess/bench/results/h200-2026-12-04-issue17-cells-alloc/poolsum.py $w/b-$1.pool > $w/$1.sum; rm -f $w/b-$1.pool
}
line new1 $x/prt-bricks; sum new1
line cur $cur/prt-bricks; sum cur
line new2 $x/prt-bricks; sum new2
line w24 $x/prt-bricks "--cell-workers 24"; sum w24
line w32 $x/prt-bricks "--cell-workers 32"; sum w32
for v in new1 new2 w24 w32; do
  cmp -s $w/cur.sum $w/$v.sum && echo "500M bricks $v: sections equal to cur" || echo "500M bricks $v: SECTIONS DIFFER"
done
echo "ALL_DONE $((SECONDS - t0)) s"
