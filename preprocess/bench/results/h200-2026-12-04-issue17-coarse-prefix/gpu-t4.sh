#!/usr/bin/env bash
# Issue 17 (H200): why the 500M close view's primary rays run 1.35 Grays/s (1.86 on 2026-11-29): the
# persistent megakernel's queue orders (mega: heavy items first; mega-fifo: image order), LOD stop
# on and off, streamed under pool/8 and in core; two rounds.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/t4.txt") 2>&1
rm -rf /tmp/ab; mkdir -p /tmp/ab; python3 -c "import tarfile; tarfile.open('build-ab/pack.tar.xz').extractall('/tmp/ab')"
bin=/tmp/ab/bin; w=/tmp/w500; mkdir -p $w
$bin/prt-synth room -n 500000000 -o $w/s.pool --quiet; $bin/prt-bricks $w/s.pool -o $w/b.pool --memory 12G --quiet; rm -f $w/s.pool
cam="--eye 0.05,-0.2,0.2 --look-at -0.3,-0.6,-0.4 --up 0,1,0 --fov 50 --width 1024 --height 1024"
pool=$(stat -c %s $w/b.pool); budget=$(( pool / 8 ))
for r in 1 2; do
for k in "--kernel mega" "--kernel mega-fifo" "--kernel mega --lod-pixels 0" "--kernel mega-fifo --lod-pixels 0"; do
  echo "== $k (pool/8)"; $bin/prt-bench --backend cuda $w/b.pool --gpu-budget $budget $cam --frames 30 --warmup 5 --scenarios primary $k 2>&1 | grep -E "^primary +[0-9]" | tail -1
done
echo "== in core, mega"; $bin/prt-bench --backend cuda $w/b.pool $cam --frames 30 --warmup 5 --scenarios primary 2>&1 | grep -E "^primary +[0-9]" | tail -1
done
