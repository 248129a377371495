#!/usr/bin/env bash
# Issue 19 on the GPU host, 2026-12-01: prt_batch_test (it failed in gpu-i2.sh's ctest run, whose
# log kept no output) with the carried dev-VM tools, then gpu-i1.sh again with the final prt-iso
# (.ab/new/bin: this tree, far corners in their own pass) against the base.
# Usage (repository root): bash preprocess/bench/results/h200-2026-12-01-issue19-iso/gpu-i3.sh
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"
bash tests/scripts/prt_batch_test.sh scripts/prt-batch "$PWD/.ab/new/bin" > "$out/batch-test.txt" 2>&1
echo "prt_batch_test exit $?" | tee -a "$out/batch-test.txt"; grep -E "FAILED|failed checks" "$out/batch-test.txt"
python3 -c "import xxhash" 2>&1 | tail -1; python3 -c "import dask, distributed" 2>&1 | tail -1
LOG=i3 bash "$(dirname "$0")/gpu-i1.sh"
