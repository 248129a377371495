#!/usr/bin/env bash
# Issue 19 (H200): the landed tree; ISO of the culled room (the pool alone, prt-bench's default
# view of it), every scenario alone in its own process: image order (mega-fifo) against heavy
# items first (mega), two rounds (the README's 2026-12-03 ISO figures ran the scenarios in one process).
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/u8.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; t0=$SECONDS
rm -rf /tmp/ab; mkdir -p /tmp/ab
python3 -c "import tarfile; tarfile.open('build-ab/pack.tar.xz').extractall('/tmp/ab')"
x=/tmp/ab/bin; w=/tmp/u8; mkdir -p $w; q=--quiet
$x/prt-bench --backend cuda --save-pool $w/room.pool --frames 1 --warmup 0 --scenarios primary $q > /dev/null 2>&1
$x/prt-cull $w/room.pool -o $w/culled.pool $q && $x/prt-iso $w/culled.pool -o $w/surf.pool $q
echo "pools done $((SECONDS - t0)) s"
alone() {  # alone LABEL SCENARIOS ARGS...
  local label=$1 scs=$2; shift 2; local line="$label"
  for sc in ${scs//,/ }; do
    $x/prt-bench --backend cuda --frames 30 --warmup 5 --json $w/b.json "$@" --scenarios $sc > /dev/null 2> $w/err.txt \
      || { line="$line $sc failed"; continue; }
    line="$line $(python3 -c "import json; s=json.load(open('$w/b.json'))['scenarios'][0]; print('%s %.3f (%d)' % (s['name'], s['grays_per_s'], s['heavy_first_frames']))")"
  done
  echo "$line"
}
for r in 1 2; do for k in mega-fifo mega; do
  alone "iso culled alone $k" primary,shadow,full4 $w/surf.pool --surface iso --kernel $k
  echo "iso culled together $k: $($x/prt-bench --backend cuda --frames 30 --warmup 5 --json $w/b.json $w/surf.pool --surface iso --kernel $k --scenarios primary,shadow,full4 > /dev/null 2>&1; python3 -c "import json; print(' '.join('%s %.3f' % (s['name'], s['grays_per_s']) for s in json.load(open('$w/b.json'))['scenarios']))")"
done; done
echo "ALL_DONE $((SECONDS - t0)) s"
