#!/usr/bin/env bash
# Issue 17 (H200), 2026-12-04: copies through page-locked chunks (device_buffer.h, Staging; gpu-a7
# found the GPU builder's kernels at 7 ms of a 1M room's 340 ms and its download at 96-108 ms).
# The GPU tests of the octree and the culling; prt-octree --backend cuda on the 1M and 10M rooms;
# prt-bricks from points on the 100M room with the previous commit's tools (pack.tar.xz, `head`)
# and this tree's (new.tar.xz, `new`), sections compared; then the 500M room with `new`.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/a8.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; t0=$SECONDS; root=$PWD
here=$root/preprocess/bench/results/h200-2026-12-04-issue17-cells-alloc
rm -rf /tmp/ab; mkdir -p /tmp/ab
python3 -c "import tarfile; tarfile.open('build-ab/pack.tar.xz').extractall('/tmp/ab'); tarfile.open('build-ab/new.tar.xz').extractall('/tmp/ab')"
head=/tmp/ab/bin; new=/tmp/ab/new; w=/tmp/w8; mkdir -p $w
mkdir -p /work/main/build-cu && ln -sfn $new /work/main/build-cu/bin
for t in prt_octree_gpu_tests prt_cull_gpu_tests; do
  echo "$t: $(PRT_BIN_DIR=$new $new/$t 2>&1 | grep -E '^\[  (PASSED|FAILED|SKIPPED)' | tr '\n' ' ')"
done
for n in 1000000 10000000; do
  $head/prt-synth room -n $n -o $w/r.pool --quiet && $head/prt-radii $w/r.pool -o $w/r.pool --quiet
  for who in head new; do
    b=$head; [ $who = new ] && b=$new
    for r in 1 2; do
      $b/prt-octree $w/r.pool -o $w/o-$who.pool --backend cuda --quiet --stats-json $w/o.json
      python3 -c "import json; s=json.load(open('$w/o.json')); print('$n $who prt-octree cuda: build %.3f s' % s['build_seconds'])"
    done
  done
  diff <(python3 $here/poolsum.py $w/o-head.pool) <(python3 $here/poolsum.py $w/o-new.pool) > /dev/null && echo "sections equal" || echo "SECTIONS DIFFER"
done
line() {  # label binary pool
  /usr/bin/time -f "%e s wall, %U s user, %S s sys, peak RSS %M KB" $2/prt-bricks $3 -o $w/b-$1.pool --memory 12G --quiet \
    --stats-json $w/st-$1.json 2>$w/time.txt; echo -n "$1: $(tail -1 $w/time.txt) "
  python3 -c "
import json; s = json.load(open('$w/st-$1.json'))
print(' build %.1f s, %.2fM pts/s; summed: octree %.1f cull %.1f bricks %.1f partition %.1f assemble %.1f' % (s['build_seconds'], s['points_per_second'] / 1e6, s['seconds']['octree'], s['seconds']['cull'], s['seconds']['bricks'], s['seconds']['partition'], s['seconds']['assemble']))"
}
$head/prt-synth room -n 100000000 -o $w/s100.pool --quiet
for r in 1 2; do line head100-$r $head $w/s100.pool; line new100-$r $new $w/s100.pool; done
diff <(python3 $here/poolsum.py $w/b-head100-1.pool) <(python3 $here/poolsum.py $w/b-new100-1.pool) > /dev/null && echo "100M sections equal" || echo "100M SECTIONS DIFFER"
rm -f $w/b-*.pool $w/s100.pool
echo "100M done $((SECONDS - t0)) s"
if [ $((SECONDS - t0)) -lt 120 ]; then
  $head/prt-synth room -n 500000000 -o $w/s500.pool --quiet
  line new500 $new $w/s500.pool
  cp $w/st-new500.json $out/bricks500-staged.json
fi
echo "ALL_DONE $((SECONDS - t0)) s"
