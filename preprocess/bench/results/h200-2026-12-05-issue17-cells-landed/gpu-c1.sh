#!/usr/bin/env bash
# Issue 17, 2026-12-05: a cell's octree built, culled and compacted on the GPU (build_culled_cell),
# rewritten after the branch of the morning was lost, built on the dev VM and carried
# (build-ab/pack.tar.xz): every GPU test program, then the 500M room from points (prt-synth's pool
# straight into prt-bricks, --memory 12G) with main a66bd54's prt-bricks (build-ab/cur.tar.xz) and
# this tree's, sections compared.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/c1.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; t0=$SECONDS; root=$PWD
rm -rf /tmp/ab; mkdir -p /tmp/ab
nvidia-smi --query-gpu=memory.used,memory.total --format=csv,noheader
python3 -c "import tarfile; tarfile.open('build-ab/pack.tar.xz').extractall('/tmp/ab'); tarfile.open('build-ab/cur.tar.xz').extractall('/tmp/ab')"
x=/tmp/ab/bin; cur=/tmp/ab/cur; w=/tmp/wc1; mkdir -p $w /tmp/c1
mkdir -p /work/shared/data/bezier && cp build-ab/bezier/* /work/shared/data/bezier/
mkdir -p /work/main/build-cu && ln -sfn "$x" /work/main/build-cu/bin
for t in $x/*_gpu_tests; do
  b=$(basename $t); PRT_BIN_DIR=$x timeout 240 $t > /tmp/c1/$b.log 2>&1
  echo "$b rc $? $(grep -E '^\[  (PASSED|FAILED|SKIPPED)' /tmp/c1/$b.log | tr '\n' ' ')"
  grep -B2 -A6 "Failure" /tmp/c1/$b.log | head -20
done
tar -czf $out/gpu-test-logs-c1.tar.gz -C /tmp/c1 $(cd /tmp/c1 && ls *_gpu_tests.log)
echo "tests done $((SECONDS - t0)) s"
$x/prt-synth room -n 500000000 -o $w/s.pool --quiet
echo "synth done $((SECONDS - t0)) s"
line() {  # label binary
  /usr/bin/time -f "%e s wall, %U s user, %S s sys, peak RSS %M KB" $2 $w/s.pool -o $w/b-$1.pool --memory 12G --quiet \
    --stats-json $out/bricks500-$1.json 2>$w/time.txt; echo -n "$1: $(tail -1 $w/time.txt) "
  python3 -c "
import json, os; s = json.load(open('$out/bricks500-$1.json'))
print(' total %.1f s, build %.1f s, %.2fM pts/s; summed: octree %.1f cull %.1f bricks %.1f partition %.1f assemble %.1f; %.2f B/point' % (s['total_seconds'], s['build_seconds'], s['points_per_second'] / 1e6, s['seconds']['octree'], s['seconds']['cull'], s['seconds']['bricks'], s['seconds']['partition'], s['seconds']['assemble'], os.path.getsize('$w/b-$1.pool') / 5e8))
print('   cells', s['cells'], 'on device', s.get('cells_culled_on_device'), 'partition passes', s.get('partition_passes'), 'radii', s['radii'], 'peak RSS', s['peak_rss_bytes'])"
}
line new $x/prt-bricks
line cur $cur/prt-bricks
diff <(python3 $root/preprocess/bench/results/h200-2026-12-04-issue17-cells-alloc/poolsum.py $w/b-cur.pool) <(python3 $root/preprocess/bench/results/h200-2026-12-04-issue17-cells-alloc/poolsum.py $w/b-new.pool) > /dev/null \
  && echo "500M bricks: sections equal" || echo "500M bricks: SECTIONS DIFFER"
echo "ALL_DONE $((SECONDS - t0)) s"
