#!/usr/bin/env bash
# Issue 19: why the BVH walk is slower on the GPU than the kd walk on a sphere: Nsight Compute on
# prt_mls_gpu_tests' trace_kernel, launch 0 (BVH walk) and launch 12 (kd walk), pack10.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/b2.txt") 2>&1
rm -rf /tmp/ab; mkdir -p /tmp/ab
python3 -c "import tarfile; tarfile.open('build-ab/pack10.tar.xz').extractall('/tmp/ab')"
x=/tmp/ab/p10
NCU=$(command -v ncu || ls /usr/local/cuda/bin/ncu 2>/dev/null | head -1)
S="--section SpeedOfLight --section LaunchStats --section Occupancy --section WarpStateStats --section InstructionStats --section SchedulerStats --section MemoryWorkloadAnalysis --section SourceCounters"
for skip in 0 12; do
  echo "=== trace_kernel launch $skip"
  $NCU -k regex:trace_kernel --launch-skip $skip --launch-count 1 $S --import-source no $x/prt_mls_gpu_tests 2>&1 | grep -v "^\[ \|^==PROF==\|Running main\|^$" | head -150
done
