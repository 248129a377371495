#!/usr/bin/env bash
# Issue 19, patches (H200), experiment (branch wip-leaf-slabs, not landed): leaf slabs with the
# deflated restart, the same binaries (pack18) on pools with and without patch_leaf_slabs.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/p6.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; t0=$SECONDS
rm -rf /tmp/ab; mkdir -p /tmp/ab
python3 -c "import tarfile; tarfile.open('build-ab/pack18.tar.xz').extractall('/tmp/ab')"
n=/tmp/ab/p18; w=/tmp/p6; mkdir -p $w; q=--quiet
for m in teapot bigguy teacup; do
  src=build-ab/bezier/$m; [ $m = teapot ] && src=build-ab/bezier/teapot.bpt
  $n/prt-patches $src -o $w/$m-slabs.pool $q; $n/prt-patches $src -o $w/$m-plain.pool --no-slabs $q
done
ls -la $w
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
for r in 1 2; do for m in teapot bigguy teacup; do for v in plain slabs; do
  bench "$m $v" $w/$m-$v.pool --max-bounces 1 --scenarios primary,shadow,reflect4
done; done; done
for m in teapot teacup; do for v in plain slabs; do
  $n/prt-play $w/$m-$v.pool --backend cuda --max-bounces 1 --width 1024 --height 1024 --out $w/$m-$v.ppm $q
done
python3 - $w/$m-plain.ppm $w/$m-slabs.ppm $m <<'PY'
import numpy as np, sys
def rd(p):
    d = open(p, 'rb').read(); parts = d.split(maxsplit=4); w, h = int(parts[1]), int(parts[2])
    return np.frombuffer(d[-w * h * 3:], np.uint8).reshape(h, w, 3).astype(int)
a, b = rd(sys.argv[1]), rd(sys.argv[2]); diff = np.abs(a - b).max(axis=2)
print('%s 1024 image plain vs slabs: pixels differing %d (by more than 8: %d) of %d, max %d' % (sys.argv[3], (diff > 0).sum(), (diff > 8).sum(), diff.size, diff.max()))
PY
done
echo "ALL_DONE $((SECONDS - t0)) s"
