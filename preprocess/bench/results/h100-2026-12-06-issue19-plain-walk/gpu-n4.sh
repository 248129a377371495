#!/usr/bin/env bash
# Issue 19 (n4): the 10M sphere's ISO primary rays with the plain walk at 2, 3 and 4 blocks per SM
# (an experiment build with plain ISO kernels at 2 and 4, build-ab/n4.tar.xz), two rounds. Makes
# the 10M sphere's ISO when n1's pools are gone (a fresh machine).
NAME=n4 TARS="tools5.tar.xz n4.tar.xz"
source preprocess/bench/results/h100-2026-12-05-issue17-radii-neighbours/lib500.sh
nb=/tmp/ab/n4/prt-bench; x=$kall; q=--quiet
if [ -f /tmp/wn1/is10.pool ]; then w=/tmp/wn1; else
  $x/prt-synth sphere -n 10000000 -o $w/s10.pool $q && $x/prt-radii $w/s10.pool -o $w/s10.pool --backend cuda $q \
    && $x/prt-octree $w/s10.pool -o $w/s10.pool $q && $x/prt-cull $w/s10.pool -o $w/cs10.pool $q \
    && $x/prt-iso $w/cs10.pool -o $w/is10.pool $q
fi
echo "pool ready $((SECONDS - t0)) s"
sph="--eye 0,0,3 --look-at 0,0,0 --up 0,1,0 --fov 45"
for r in 1 2; do
  for b in 3 2 4; do
    $nb --backend cuda --frames 100 --warmup 10 --json $w/b4.json $w/is10.pool $sph --surface iso --iso-walk plain --min-blocks $b --scenarios primary > /dev/null 2> $w/err4.txt \
      || { echo "r$r plain $b blocks failed: $(tail -1 $w/err4.txt)"; continue; }
    echo "r$r plain, $b blocks per SM: $(python3 -c "import json; s=json.load(open('$w/b4.json'))['scenarios'][0]; print('%.3f' % s['grays_per_s'])")"
  done
done
echo "ALL_DONE $((SECONDS - t0)) s"
