#!/usr/bin/env bash
# Issue 19, patches (H200): the patch kernels at 3 blocks per SM (80 registers) against 2 (128).
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/q1.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; t0=$SECONDS
rm -rf /tmp/ab; mkdir -p /tmp/ab
for p in pack10 pack20; do python3 -c "import tarfile; tarfile.open('build-ab/$p.tar.xz').extractall('/tmp/ab')"; done
x=/tmp/ab/p10; n=/tmp/ab/p20; w=/tmp/q1; mkdir -p $w; q=--quiet
$x/prt-patches build-ab/bezier/teapot.bpt -o $w/teapot.pool $q
$x/prt-patches build-ab/bezier/bigguy -o $w/bigguy.pool $q
bench() {  # bench LABEL ARGS...
  local label=$1; shift
  $n/prt-bench --backend cuda --frames 30 --warmup 5 --json $w/b.json "$@" > /dev/null 2> $w/err.txt \
    || { echo "$label failed: $(tail -2 $w/err.txt)"; return; }
  python3 - "$label" $w/b.json <<'PY'
import json, sys
j = json.load(open(sys.argv[2]))
print(sys.argv[1].ljust(20), ' '.join('%s %.3f' % (x['name'], x['grays_per_s']) for x in j['scenarios']), flush=True)
PY
}
for r in 1 2; do for mb in 2 3; do
  bench "teapot mb$mb" $w/teapot.pool --max-bounces 1 --scenarios primary,shadow,reflect4 --min-blocks $mb
  bench "bigguy mb$mb" $w/bigguy.pool --max-bounces 1 --scenarios primary,shadow,reflect4 --min-blocks $mb
done; done
echo "ALL_DONE $((SECONDS - t0)) s"
