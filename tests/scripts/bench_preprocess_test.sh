#!/usr/bin/env bash
# scripts/bench-preprocess.sh on a small model: the chain runs on 1 core (and 2 where the process
# has them), the table has a row per step and a total whose seconds are the steps' sum; a missing
# tool, a thread count above the cores and a FRESH other than 0 or 1 are one-line errors; FRESH=1
# runs the chain into new files.
# Usage: bench_preprocess_test.sh SCRIPT BIN_DIR   (exit 77: skipped)
set -euo pipefail
script=$1
bin=$2
for t in prt-import prt-radii prt-octree prt-cull prt-iso; do
    [ -x "$bin/$t" ] || { echo "skip: $bin/$t not built"; exit 77; }
done
command -v taskset >/dev/null || { echo "skip: no taskset"; exit 77; }
build=$(mktemp -d "${TMPDIR:-/tmp}/prt-bench-preprocess-test.XXXXXX")
trap 'rm -rf "$build"' EXIT
ln -s "$(cd "$bin" && pwd)" "$build/bin"
counts=1
[ "$(nproc)" -ge 2 ] && counts=1,2
out=$(bash "$script" "$build" 3000 "$counts" 1)
echo "$out"
for row in prt-import prt-radii prt-octree prt-cull prt-iso total; do
    echo "$out" | grep -q "^$row " || { echo "FAIL: no row $row"; exit 1; }
done
# total = sum of the steps, in the first thread count's column
echo "$out" | awk '$1 ~ /^prt-/ { s += $2 } $1 == "total" { t = $2 }
    END { if (s - t > 0.002 || t - s > 0.002) { print "FAIL: total " t " != sum " s; exit 1 } }'
# FRESH=1: each run into a new file (two runs, the second after removing the first's outputs)
fresh=$(FRESH=1 bash "$script" "$build" 3000 1 2)
echo "$fresh" | grep -q "each run into a new file" || { echo "FAIL: FRESH=1 not announced: $fresh"; exit 1; }
echo "$fresh" | grep -q "^total " || { echo "FAIL: FRESH=1 gave no total: $fresh"; exit 1; }
if err=$(FRESH=yes bash "$script" "$build" 3000 1 1 2>&1); then echo "FAIL: FRESH=yes accepted"; exit 1; fi
echo "$err" | grep -q "FRESH must be 0 or 1" || { echo "FAIL: $err"; exit 1; }
if err=$(bash "$script" "$build" 3000 "$(($(nproc) + 1))" 1 2>&1); then
    echo "FAIL: more threads than cores accepted"; exit 1
fi
echo "$err" | grep -q "cores" || { echo "FAIL: $err"; exit 1; }
mkdir -p "$build/empty/bin"
if err=$(bash "$script" "$build/empty" 3000 1 1 2>&1); then echo "FAIL: missing tools accepted"; exit 1; fi
if [ "$(echo "$err" | wc -l)" != 1 ] || ! echo "$err" | grep -q "prt-import is missing"; then
    echo "FAIL: $err"
    exit 1
fi
echo "bench_preprocess_test: ok"
