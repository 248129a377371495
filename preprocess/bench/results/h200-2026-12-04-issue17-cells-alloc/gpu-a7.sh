#!/usr/bin/env bash
# Issue 17 (H200), 2026-12-04: where the GPU octree builder's time goes. prt-octree --backend cuda
# built with timing-patch.diff (a stream synchronization and a clock read at each phase's end,
# PRT_OCTREE_CUDA_TIMING=1; not committed) on the 1M and 10M rooms, alone in the process, twice each.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/a7.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; t0=$SECONDS
rm -rf /tmp/ab; mkdir -p /tmp/ab
python3 -c "import tarfile; tarfile.open('build-ab/pack.tar.xz').extractall('/tmp/ab'); tarfile.open('build-ab/timing.tar.xz').extractall('/tmp/ab')"
x=/tmp/ab/bin; w=/tmp/w7; mkdir -p $w
for n in 1000000 10000000; do
  $x/prt-synth room -n $n -o $w/r.pool --quiet && $x/prt-radii $w/r.pool -o $w/r.pool --quiet
  for r in 1 2; do
    PRT_OCTREE_CUDA_TIMING=1 $x/prt-octree-timing $w/r.pool -o $w/o.pool --backend cuda --quiet --stats-json $w/o.json 2>&1 | tail -1
    python3 -c "import json; s=json.load(open('$w/o.json')); print('  build %.3f s, %d stored' % (s['build_seconds'], s['stored_splats']))"
  done
  $x/prt-octree $w/r.pool -o $w/o.pool --backend cpu --quiet --stats-json $w/o.json
  python3 -c "import json; s=json.load(open('$w/o.json')); print('  cpu (16 threads): build %.3f s' % s['build_seconds'])"
done
echo "ALL_DONE $((SECONDS - t0)) s"
