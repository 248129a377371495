#!/usr/bin/env bash
# Issue 17 (H200), gpu-a3.sh again with the culling on a stream of its own with stream-ordered
# memory too (no cudaDeviceSynchronize, no cudaFree beside the other cells' octree builds).
# on the GPU (runtime/cuda/src/octree_build.cu). The GPU test (CUDA against the CPU builder, byte for
# byte); prt-octree --backend cpu / cuda on a 1M room; prt-bricks from points with the landed tools
# (cells' octrees on the CPU) against this tree's (--backend auto: on the GPU), a 20M and a 100M
# room, sections compared (poolsum.py: every section's checksum, provenance aside).
# Carried: build-ab/pack.tar.xz (the landed tools), build-ab/new.tar.xz (this tree's prt-bricks,
# prt-octree, prt_octree_gpu_tests; built on the dev VM).
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/a4.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; t0=$SECONDS; root=$PWD
here=$root/preprocess/bench/results/h200-2026-12-04-issue17-cells-alloc
rm -rf /tmp/ab; mkdir -p /tmp/ab
python3 -c "import tarfile; tarfile.open('build-ab/pack.tar.xz').extractall('/tmp/ab'); tarfile.open('build-ab/new.tar.xz').extractall('/tmp/ab')"
cur=/tmp/ab/bin; new=/tmp/ab/new; w=/tmp/wa2; mkdir -p $w
$new/prt_octree_gpu_tests 2>&1 | grep -E "^\[  (PASSED|FAILED|SKIPPED)|OK \]|FAILED|Failure|Expected|Which is|trace" | head -40
mkdir -p /work/main/build-cu && ln -sfn $new /work/main/build-cu/bin; PRT_BIN_DIR=$new $new/prt_cull_gpu_tests 2>&1 | grep -E "^\[  (PASSED|FAILED|SKIPPED)|FAILED|Failure" | head -20
echo "tests done $((SECONDS - t0)) s"
sum() { python3 $here/poolsum.py "$1"; }
$cur/prt-synth room -n 1000000 -o $w/r1.pool --quiet && $cur/prt-radii $w/r1.pool -o $w/r1.pool --quiet
for r in 1 2; do
  for b in cpu cuda; do
    s=$(date +%s.%N); $new/prt-octree $w/r1.pool -o $w/o1-$b.pool --backend $b --quiet --stats-json $w/o1.json
    python3 -c "import json; s=json.load(open('$w/o1.json')); print('r$r prt-octree 1M --backend $b: %.3f s wall, build %.3f s, %d stored' % ($(date +%s.%N) - $s, s['build_seconds'], s['stored_splats']))"
  done
done
diff <(sum $w/o1-cpu.pool) <(sum $w/o1-cuda.pool) > /dev/null && echo "1M octree: cpu and cuda sections equal" || echo "1M octree: SECTIONS DIFFER"
line() {  # label binary pool memory
  /usr/bin/time -f "%e s wall, %U s user, %S s sys, peak RSS %M KB" $2 $3 -o $w/b-$1.pool --memory $4 --quiet \
    --stats-json $w/st.json 2>$w/time.txt; echo -n "$1: $(tail -1 $w/time.txt) "
  python3 -c "
import json; s = json.load(open('$w/st.json'))
print(' build %.1f s, %.2fM pts/s; summed: octree %.1f cull %.1f bricks %.1f partition %.1f assemble %.1f' % (s['build_seconds'], s['points_per_second'] / 1e6, s['seconds']['octree'], s['seconds']['cull'], s['seconds']['bricks'], s['seconds']['partition'], s['seconds']['assemble']))"
}
$cur/prt-synth room -n 20000000 -o $w/s20.pool --quiet
line cur20 $cur/prt-bricks $w/s20.pool 2G; line new20 $new/prt-bricks $w/s20.pool 2G
diff <(sum $w/b-cur20.pool) <(sum $w/b-new20.pool) > /dev/null && echo "20M bricks: sections equal" || echo "20M bricks: SECTIONS DIFFER"
rm -f $w/s20.pool $w/b-*20.pool
$cur/prt-synth room -n 100000000 -o $w/s100.pool --quiet
echo "synth done $((SECONDS - t0)) s"
for r in 1 2; do
  line cur100-r$r $cur/prt-bricks $w/s100.pool 12G; line new100-r$r $new/prt-bricks $w/s100.pool 12G
  diff <(sum $w/b-cur100-r$r.pool) <(sum $w/b-new100-r$r.pool) > /dev/null && echo "100M bricks: sections equal" || echo "100M bricks: SECTIONS DIFFER"
  rm -f $w/b-*100-r$r.pool
done
echo "ALL_DONE $((SECONDS - t0)) s"
