#!/usr/bin/env bash
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/b4.txt") 2>&1
rm -rf /tmp/ab; mkdir -p /tmp/ab
python3 -c "import tarfile; tarfile.open('build-ab/pack12.tar.xz').extractall('/tmp/ab')"
x=/tmp/ab/p12/mls_gpu_lineinfo
NCU=$(command -v ncu || ls /usr/local/cuda/bin/ncu 2>/dev/null | head -1)
$NCU --version | tail -1
for skip in 0 12; do
  $NCU -k regex:trace_kernel --launch-skip $skip --launch-count 1 --section SourceCounters --section WarpStateStats --section InstructionStats --import-source yes -o /tmp/r$skip -f $x 2>&1 | grep -v "^\[" | tail -5
  $NCU -i /tmp/r$skip.ncu-rep --page source --csv --print-source cuda,sass > /tmp/s$skip.csv 2>&1; head -c 600 /tmp/s$skip.csv; echo; wc -l /tmp/s$skip.csv; gzip -c /tmp/s$skip.csv > $out/src$skip.csv.gz
done
