#!/usr/bin/env bash
# Issue 17, 2026-12-05: gpu-d3.sh cut to what a small device budget holds: the patched radii GPU
# tests, then the 500M room from points (--memory 12G, 16 cores) with main (c10383a, bin/) and knn
# (48ab991 + radii-stored-neighbours.patch, knn/), one run each; sections compared.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/d4.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader; t0=$SECONDS; root=$PWD
rm -rf /tmp/ab; mkdir -p /tmp/ab
python3 -c "import tarfile; tarfile.open('build-ab/pack.tar.xz').extractall('/tmp/ab'); tarfile.open('build-ab/knn.tar.xz').extractall('/tmp/ab'); tarfile.open('build-ab/blk.tar.xz').extractall('/tmp/ab')"
x=/tmp/ab/bin; knn=/tmp/ab/knn; blk=/tmp/ab/blk; w=/tmp/wd4; mkdir -p $w
timeout 300 $knn/prt_radii_gpu_tests > $out/prt_radii_gpu_tests-knn.log 2>&1
echo "knn prt_radii_gpu_tests rc $? $(grep -E '^\[  (PASSED|FAILED|SKIPPED)|^\[       OK' $out/prt_radii_gpu_tests-knn.log | tr '\n' ' ')"
grep -B2 -A6 "Failure" $out/prt_radii_gpu_tests-knn.log | head -30
echo "tests done $((SECONDS - t0)) s"
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
line knn1 $knn/prt-bricks; sum knn1
for v in knn1; do
  cmp -s $w/main1.sum $w/$v.sum && echo "500M bricks $v: sections equal to main1" || echo "500M bricks $v: SECTIONS DIFFER"
done
echo "ALL_DONE $((SECONDS - t0)) s"
