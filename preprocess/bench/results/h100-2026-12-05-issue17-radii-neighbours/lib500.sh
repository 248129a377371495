# Sourced by gpu-d1.sh .. gpu-d5.sh: the shared steps of one call on the GPU host. Before sourcing,
# set NAME (the log's name) and TARS (the carried tarballs of build-ab/ to unpack into /tmp/ab:
# pack.tar.xz gives bin/, knn.tar.xz knn/, blk.tar.xz blk/, kall.tar.xz kall/).
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/$NAME.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader; t0=$SECONDS; root=$PWD
rm -rf /tmp/ab; mkdir -p /tmp/ab
for t in $TARS; do python3 -c "import tarfile, sys; tarfile.open(sys.argv[1]).extractall('/tmp/ab')" build-ab/$t; done
x=/tmp/ab/bin; knn=/tmp/ab/knn; blk=/tmp/ab/blk; kall=/tmp/ab/kall; w=/tmp/w$NAME; mkdir -p $w

radii_tests() {  # the patched radii GPU tests (the CPU's radii bit for bit, both ways to the neighbours equal)
  timeout 300 $knn/prt_radii_gpu_tests > $out/prt_radii_gpu_tests-knn.log 2>&1
  echo "knn prt_radii_gpu_tests rc $? $(grep -E '^\[  (PASSED|FAILED|SKIPPED)|^\[       OK' $out/prt_radii_gpu_tests-knn.log | tr '\n' ' ')"
  grep -B2 -A6 "Failure" $out/prt_radii_gpu_tests-knn.log | head -30
  echo "tests done $((SECONDS - t0)) s"
}
gpu_tests() {  # every GPU test program of kall/ (the whole tree with the radii patch), its tools beside it
  mkdir -p /work/shared/data/bezier && cp -r build-ab/bezier/* /work/shared/data/bezier/
  mkdir -p $root/build-cu && ln -sfn "$kall" $root/build-cu/bin; mkdir -p /tmp/gt
  for t in $kall/*_gpu_tests; do
    local b=$(basename $t); PRT_BIN_DIR=$kall timeout 240 $t > /tmp/gt/$b.log 2>&1
    echo "$b rc $? $(grep -E '^\[  (PASSED|FAILED|SKIPPED)' /tmp/gt/$b.log | tr '\n' ' ')"
    grep -B2 -A6 "Failure" /tmp/gt/$b.log | head -20
  done
  tar -czf $out/gpu-test-logs-$NAME.tar.gz -C /tmp/gt $(cd /tmp/gt && ls)
  echo "tests done $((SECONDS - t0)) s"
}
synth() {  # the 500M room (prt-synth's pool, fed straight to prt-bricks)
  $x/prt-synth room -n 500000000 -o $w/s.pool --quiet
  echo "synth done $((SECONDS - t0)) s"
}
line() {  # label binary [options]: the 500M room from points, --memory 12G
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
compare() {  # reference label, then the labels compared with it
  local ref=$1; shift
  for v in "$@"; do
    cmp -s $w/$ref.sum $w/$v.sum && echo "500M bricks $v: sections equal to $ref" || echo "500M bricks $v: SECTIONS DIFFER"
  done
  echo "ALL_DONE $((SECONDS - t0)) s"
}
