#!/usr/bin/env bash
# Issue 19 (H200): u2's 500M close view (pool/8) chose heavy items first by time and stayed there,
# 1.36 Grays/s against image order's 1.82, though its probe of image order should have switched.
# Per-frame ms and heavy items of the timed order and of heavy first, primary rays, streamed and
# in core.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/u6.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; t0=$SECONDS
rm -rf /tmp/ab; mkdir -p /tmp/ab; python3 -c "import tarfile; tarfile.open('build-ab/pack.tar.xz').extractall('/tmp/ab')"
bin=/tmp/ab/bin; w=/tmp/w500; mkdir -p $w
[ -s $w/b.pool ] || { $bin/prt-synth room -n 500000000 -o $w/s.pool --quiet; $bin/prt-bricks $w/s.pool -o $w/b.pool --memory 12G --quiet; rm -f $w/s.pool; }
echo "pool done $((SECONDS - t0)) s"
cam="--eye 0.05,-0.2,0.2 --look-at -0.3,-0.6,-0.4 --up 0,1,0 --fov 50 --width 1024 --height 1024"
pool=$(stat -c %s $w/b.pool); budget=$(( pool / 8 ))
for b in "--gpu-budget $budget" ""; do for k in mega mega-heavy mega-fifo; do
  $bin/prt-bench --backend cuda $w/b.pool $b $cam --frames 40 --warmup 5 --scenarios primary --kernel $k --json $w/b.json > /dev/null 2>&1
  echo "== $k ${b:-in core}"
  python3 -c "
import json
s = json.load(open('$w/b.json'))['scenarios'][0]
print(' %.3f Grays/s' % s['grays_per_s'], 'streaming passes:', (s.get('streaming') or {}).get('passes', '-'))
print(' ms', ' '.join('%.3f' % v for v in s['frames_ms']))
print(' heavy', s['frames_heavy_first_items'])"
done; done
echo "ALL_DONE $((SECONDS - t0)) s"
