#!/usr/bin/env bash
# Issue 19, patches (H200): the teapot's primary and one-reflection frames, baseline and Nsight
# Compute (source counters, warp states, memory) on the patch megakernels; pack13/pack10 binaries.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/p1.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; t0=$SECONDS
rm -rf /tmp/ab; mkdir -p /tmp/ab
for p in pack10 pack13; do python3 -c "import tarfile; tarfile.open('build-ab/$p.tar.xz').extractall('/tmp/ab')"; done
cp /tmp/ab/p13/* /tmp/ab/p10/; x=/tmp/ab/p10; w=/tmp/p1; mkdir -p $w; q=--quiet
$x/prt-patches build-ab/teapot.bpt -o $w/teapot.pool $q
bench() {  # bench LABEL ARGS...
  local label=$1; shift
  $x/prt-bench --backend cuda --frames 30 --warmup 5 --json $w/b.json "$@" > /dev/null 2> $w/err.txt \
    || { echo "$label failed: $(tail -2 $w/err.txt)"; return; }
  python3 - "$label" $w/b.json <<'PY'
import json, sys
j = json.load(open(sys.argv[2]))
print(sys.argv[1].ljust(20), ' '.join('%s %.4f (%.3f ms)' % (x['name'], x['grays_per_s'], x['median_ms']) for x in j['scenarios']), flush=True)
PY
}
for r in 1 2; do bench teapot $w/teapot.pool --max-bounces 1 --scenarios primary,shadow,reflect4; done
bench "teapot 512" $w/teapot.pool --max-bounces 1 --scenarios primary,reflect4 --width 512 --height 512
bench "teapot 2048" $w/teapot.pool --max-bounces 1 --scenarios primary,reflect4 --width 2048 --height 2048
$x/prt-play $w/teapot.pool --backend cuda --max-bounces 1 --out $out/teapot.ppm --quiet 2>&1 | tail -2
for s in primary reflect4; do
  ncu --clock-control none -k regex:render_kernel --launch-skip 4 --launch-count 1 --section SourceCounters \
    --section LaunchStats --section Occupancy --section SpeedOfLight --section MemoryWorkloadAnalysis \
    --section WarpStateStats --section ComputeWorkloadAnalysis --import-source yes -o $w/ncu-$s \
    $x/prt-bench --backend cuda --frames 1 --warmup 4 --max-bounces 1 --scenarios $s $w/teapot.pool $q > $w/ncu-$s.log 2>&1
  tail -3 $w/ncu-$s.log
  ncu -i $w/ncu-$s.ncu-rep --print-details all > $out/ncu-$s-details.txt 2>&1
  ncu -i $w/ncu-$s.ncu-rep --page source --csv --print-source cuda,sass 2>/dev/null | gzip > $out/ncu-$s-source.csv.gz
  ls -la $out/ncu-$s-source.csv.gz
done
echo "ALL_DONE $((SECONDS - t0)) s"
