#!/usr/bin/env bash
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/s3.txt") 2>&1
bin=$PWD/build-cuda/bin; w=/tmp/ws; mkdir -p $w
T='%e s wall, %U user, %S sys, %M KB'
$bin/prt-synth room -n 100000000 -o $w/s100.pool --quiet; echo "synth 100M rc $?"
for cw in 16 8; do
  /usr/bin/time -f "workers $cw: $T" $bin/prt-bricks $w/s100.pool -o $w/b100.pool --memory 12G --cell-workers $cw --stats-json $out/b100-w$cw.json 2> $w/b100.err; echo "100M workers $cw rc $?"
  grep -E "s partitioning|building \(|wall," $w/b100.err
done
echo ALL_DONE
