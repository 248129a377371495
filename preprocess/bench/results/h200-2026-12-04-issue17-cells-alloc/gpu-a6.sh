#!/usr/bin/env bash
# Issue 17 (H200), 2026-12-04: with the cells' octrees on the GPU, a cell worker waits for the GPU
# part of its time; more cell workers than threads (--cell-workers; -j 16, so one thread each, and
# --memory shared: smaller cells) let the others' CPU work fill those waits. The 100M room with 16
# (the default), 24 and 32 workers, then the 500M room with 32; sections compared with 16's.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/a6.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; t0=$SECONDS; root=$PWD
here=$root/preprocess/bench/results/h200-2026-12-04-issue17-cells-alloc
rm -rf /tmp/ab; mkdir -p /tmp/ab; python3 -c "import tarfile; tarfile.open('build-ab/pack.tar.xz').extractall('/tmp/ab')"
x=/tmp/ab/bin; w=/tmp/w6; mkdir -p $w
line() {  # label pool workers
  /usr/bin/time -f "%e s wall, %U s user, %S s sys, peak RSS %M KB" $x/prt-bricks $2 -o $w/b-$1.pool --memory 12G \
    --cell-workers $3 --quiet --stats-json $w/st.json 2>$w/time.txt; echo -n "$1: $(tail -1 $w/time.txt) "
  python3 -c "
import json; s = json.load(open('$w/st.json'))
print(' build %.1f s, %.2fM pts/s, %d cells; summed: octree %.1f cull %.1f bricks %.1f partition %.1f assemble %.1f' % (s['build_seconds'], s['points_per_second'] / 1e6, s.get('cells', 0), s['seconds']['octree'], s['seconds']['cull'], s['seconds']['bricks'], s['seconds']['partition'], s['seconds']['assemble']))"
}
same() { diff <(python3 $here/poolsum.py $1) <(python3 $here/poolsum.py $2) > /dev/null && echo "sections equal" || echo "SECTIONS DIFFER"; }
$x/prt-synth room -n 100000000 -o $w/s100.pool --quiet
for cw in 16 24 32; do line cw$cw $w/s100.pool $cw; done
same $w/b-cw16.pool $w/b-cw32.pool; same $w/b-cw16.pool $w/b-cw24.pool
rm -f $w/b-cw*.pool $w/s100.pool
echo "100M done $((SECONDS - t0)) s"
$x/prt-synth room -n 500000000 -o $w/s500.pool --quiet
line 500-cw32 $w/s500.pool 32
echo "ALL_DONE $((SECONDS - t0)) s"
