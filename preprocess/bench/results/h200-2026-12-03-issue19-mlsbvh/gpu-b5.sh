#!/usr/bin/env bash
# Issue 19: the BVH walk's traversal loop with one exit (state flag, no break): pack12 test kernel
# (-lineinfo): timings, then source-level Nsight Compute, launch 0 (BVH) against 12 (kd).
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/b5.txt") 2>&1
rm -rf /tmp/ab; mkdir -p /tmp/ab
python3 -c "import tarfile; tarfile.open('build-ab/pack12.tar.xz').extractall('/tmp/ab')"
x=/tmp/ab/p12/mls_gpu_lineinfo
$x 2>&1 | grep -E "measured|PASSED|FAILED"
NCU=$(command -v ncu || ls /usr/local/cuda/bin/ncu 2>/dev/null | head -1)
for skip in 0; do
  $NCU -k regex:trace_kernel --launch-skip $skip --launch-count 1 --section SourceCounters --section WarpStateStats --section InstructionStats --import-source yes -o /tmp/r$skip -f $x > /dev/null 2>&1
  $NCU -i /tmp/r$skip.ncu-rep --page source --csv --print-source cuda,sass | gzip > $out/src$skip.csv.gz
done
