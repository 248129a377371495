#!/usr/bin/env bash
# Node boxes: how often a ray entering an internal node meets its box (surface-area ratio of the box
# within the cell to the cell, Cauchy), per model (sah.py, numpy).
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/x6.txt") 2>&1
root=$PWD; rm -rf /tmp/ab; mkdir -p /tmp/ab; python3 -c "import tarfile; tarfile.open('build-ab/pack.tar.xz').extractall('/tmp/ab')"
new=/tmp/ab/new; w=/tmp/x6; rm -rf $w; mkdir -p $w; q=--quiet
$new/prt-bench --save-pool $w/room.pool --frames 1 --warmup 0 --width 16 --height 16 --scenarios primary $q > /dev/null
$new/prt-cull $w/room.pool -o $w/culled.pool $q
for n in 1000000 10000000; do
  $new/prt-synth sphere -n $n -o $w/s$n.pool $q && $new/prt-radii $w/s$n.pool -o $w/s$n.pool --backend cuda $q \
    && $new/prt-octree $w/s$n.pool -o $w/s$n.pool $q && $new/prt-cull $w/s$n.pool -o $w/s$n.pool $q || echo "sphere $n failed"
done
for p in culled room s1000000 s10000000; do python3 build-ab/sah.py $w/$p.pool build-ab/x5/prt-info; done
echo ALL_DONE
