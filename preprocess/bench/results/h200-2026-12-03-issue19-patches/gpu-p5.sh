#!/usr/bin/env bash
# Issue 19, patches (H200): Newton's patch evaluation without the twist vector (pack17) against the
# apex commit (pack16's prt-bench); the GPU test programs of pack17 first; teapot and Bigguy,
# alternating, three rounds; the teapot images compared.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/p5.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; t0=$SECONDS
rm -rf /tmp/ab; mkdir -p /tmp/ab
for p in pack10 pack16 pack17; do python3 -c "import tarfile; tarfile.open('build-ab/$p.tar.xz').extractall('/tmp/ab')"; done
x=/tmp/ab/p10; b=/tmp/ab/p16; n=/tmp/ab/p17; w=/tmp/p5; mkdir -p $w; q=--quiet
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
for r in 1 2 3; do for v in base new; do bin=$b; [ $v = new ] && bin=$n
  bench "teapot $v" $bin $w/teapot.pool --max-bounces 1 --scenarios primary,shadow,reflect4
  bench "bigguy $v" $bin $w/bigguy.pool --max-bounces 1 --scenarios primary,shadow,reflect4
done; done
$n/prt-play $w/teapot.pool --backend cuda --max-bounces 1 --width 1024 --height 1024 --out $w/teapot-new.ppm $q
$x/prt-play $w/teapot.pool --backend cuda --max-bounces 1 --width 1024 --height 1024 --out $w/teapot-base.ppm $q
cmp $w/teapot-base.ppm $w/teapot-new.ppm && echo "teapot 1024 images base (landed tools) and new identical"
echo "ALL_DONE $((SECONDS - t0)) s"
