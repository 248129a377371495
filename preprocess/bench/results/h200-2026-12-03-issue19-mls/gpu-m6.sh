#!/usr/bin/env bash
# Issue 19, MLS on the GPU (H200), sixth call: the support span widened to the 64ths of the cell
# interval around it, at least half a 64th beyond the supports (pack6), after m4 and m5 (the span
# in correctly rounded operations) failed the CPU/GPU agreement test on the flipped and noisy
# models; the GPU tests, then the benchmark against 884bfa6 (pack2).
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/m6.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; t0=$SECONDS
rm -rf /tmp/ab; mkdir -p /tmp/ab
python3 -c "import tarfile; [tarfile.open('build-ab/pack%d.tar.xz' % i).extractall('/tmp/ab') for i in (2, 6)]"
n=/tmp/ab/p2; x=/tmp/ab/p6; w=/tmp/m6; rm -rf $w; mkdir -p $w; q=--quiet
mkdir -p /work/main/build-cu && ln -sfn "$x" /work/main/build-cu/bin
for t in prt_stability_gpu_tests prt_mls_gpu_tests prt_runtime_gpu_tests prt_iso_gpu_tests; do
  PRT_BIN_DIR=$x $x/$t > $out/$t.log 2>&1; echo "$t rc $? $(grep -E '^\[  (PASSED|FAILED|SKIPPED)' $out/$t.log | tr '\n' ' ')"
done
grep -A3 "Failure" $out/prt_stability_gpu_tests.log | head -20
$n/prt-bench --save-pool $w/room.pool --frames 1 --warmup 0 --scenarios primary --backend cuda $q > /dev/null
$n/prt-cull $w/room.pool -o $w/culled.pool $q && $n/prt-iso $w/culled.pool -o $w/surf.pool $q
$n/prt-mls $w/surf.pool -o $w/mls.pool $q
$n/prt-synth sphere -n 1000000 -o $w/sphere.pool $q && $n/prt-radii $w/sphere.pool -o $w/sphere.pool $q \
  && $n/prt-mls $w/sphere.pool -o $w/sphere.pool $q
bench() {  # bench LABEL BIN ARGS...
  local label=$1 bin=$2; shift 2
  $bin/prt-bench --backend cuda --frames 20 --warmup 3 --surface mls --json $w/b.json "$@" > /dev/null 2> $w/err.txt \
    || { echo "$label failed: $(tail -2 $w/err.txt)"; return; }
  python3 - "$label" $w/b.json <<'PY'
import json, sys
j = json.load(open(sys.argv[2]))
print(sys.argv[1].ljust(22), ' '.join('%s %.4f' % (x['name'], x['grays_per_s']) for x in j['scenarios']), flush=True)
PY
}
S=primary,shadow,reflect4,full4; SPH="--eye 0,0,3 --look-at 0,0,0 --up 0,1,0 --fov 45"
for r in 1 2; do
  bench "room new" $n $w/mls.pool --scenarios $S
  bench "room clip64" $x $w/mls.pool --scenarios $S
  bench "sphere new" $n $w/sphere.pool --scenarios $S $SPH
  bench "sphere clip64" $x $w/sphere.pool --scenarios $S $SPH
done
echo "ALL_DONE $((SECONDS - t0)) s"
