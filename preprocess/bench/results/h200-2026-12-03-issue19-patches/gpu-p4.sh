#!/usr/bin/env bash
# Issue 19, patches (H200): the apex solve on projected cubics. The GPU test programs of this tree
# (pack16; the teapot data copied to the path the tests read), then prt-bench base (pack10, the
# landed tree's patch code) against new (pack16), teapot and Bigguy, alternating, two rounds.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/p4.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; t0=$SECONDS
rm -rf /tmp/ab; mkdir -p /tmp/ab
for p in pack10 pack16; do python3 -c "import tarfile; tarfile.open('build-ab/$p.tar.xz').extractall('/tmp/ab')"; done
x=/tmp/ab/p10; n=/tmp/ab/p16; w=/tmp/p4; mkdir -p $w; q=--quiet
mkdir -p /work/shared/data/bezier && cp build-ab/bezier/* /work/shared/data/bezier/ && echo "shared bezier data in place"
mkdir -p /work/main/build-cu && ln -sfn "$x" /work/main/build-cu/bin
for t in prt_patches_gpu_tests prt_runtime_gpu_tests prt_stability_gpu_tests; do
  PRT_BIN_DIR=$x timeout 300 $n/$t > $out/$t.log 2>&1; echo "$t rc $? $(grep -E '^\[  (PASSED|FAILED|SKIPPED)' $out/$t.log | tr '\n' ' ')"
done
grep -A3 "Failure" $out/*.log | head -20; grep -h "SKIPPED \]" $out/*.log | head
echo "tests done $((SECONDS - t0)) s"
$x/prt-patches build-ab/bezier/teapot.bpt -o $w/teapot.pool $q
$x/prt-patches build-ab/bezier/bigguy -o $w/bigguy.pool $q
bench() {  # bench LABEL BIN ARGS...
  local label=$1 bin=$2; shift 2
  $bin/prt-bench --backend cuda --frames 30 --warmup 5 --json $w/b.json "$@" > /dev/null 2> $w/err.txt \
    || { echo "$label failed: $(tail -2 $w/err.txt)"; return; }
  python3 - "$label" $w/b.json <<'PY'
import json, sys
j = json.load(open(sys.argv[2]))
print(sys.argv[1].ljust(20), ' '.join('%s %.3f' % (x['name'], x['grays_per_s']) for x in j['scenarios']), flush=True)
PY
}
for r in 1 2; do for v in base new; do b=$x; [ $v = new ] && b=$n
  bench "teapot $v" $b $w/teapot.pool --max-bounces 1 --scenarios primary,shadow,reflect4
  bench "bigguy $v" $b $w/bigguy.pool --max-bounces 1 --scenarios primary,shadow,reflect4
done; done
for v in base new; do b=$x; [ $v = new ] && b=$n
  bench "teapot 2048 $v" $b $w/teapot.pool --max-bounces 1 --scenarios primary,reflect4 --width 2048 --height 2048
  $b/prt-play $w/teapot.pool --backend cuda --max-bounces 1 --width 1024 --height 1024 --out $w/teapot-$v.ppm $q
done
cp $w/teapot-new.ppm $out/
python3 - $w/teapot-base.ppm $w/teapot-new.ppm <<'PY'
import numpy as np, sys
def rd(p):
    d = open(p, 'rb').read(); parts = d.split(maxsplit=4); w, h = int(parts[1]), int(parts[2])
    return np.frombuffer(d[-w * h * 3:], np.uint8).reshape(h, w, 3).astype(int)
a, b = rd(sys.argv[1]), rd(sys.argv[2]); diff = np.abs(a - b).max(axis=2)
print('teapot 1024 image base vs new: pixels differing %d of %d, max difference %d' % ((diff > 0).sum(), diff.size, diff.max()))
PY
echo "ALL_DONE $((SECONDS - t0)) s"
