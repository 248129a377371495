#!/usr/bin/env bash
# Issue 19 (n3, on n1's warm machine and pools): the 10M sphere's ISO primary rays with the plain
# walk under the megakernel's other settings (item order, mapping, L1 carveout), two rounds.
NAME=n3 TARS="n1.tar.xz"
source preprocess/bench/results/h100-2026-12-05-issue17-radii-neighbours/lib500.sh
w=/tmp/wn1; nb=/tmp/ab/n1/prt-bench; ls $w/is10.pool > /dev/null || exit 1
sph="--eye 0,0,3 --look-at 0,0,0 --up 0,1,0 --fov 45"
for r in 1 2; do
  for opt in "" "--kernel mega-fifo" "--kernel mega-static" "--mapping linear" "--default-carveout"; do
    $nb --backend cuda --frames 100 --warmup 10 --json $w/b3.json $w/is10.pool $sph --surface iso --iso-walk plain $opt --scenarios primary > /dev/null 2> $w/err3.txt
    echo "r$r plain ${opt:-default}: $(python3 -c "import json; s=json.load(open('$w/b3.json'))['scenarios'][0]; print('%.3f' % s['grays_per_s'])")"
  done
done
echo "ALL_DONE $((SECONDS - t0)) s"
