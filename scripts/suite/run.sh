#!/usr/bin/env bash
# The speed/accuracy benchmark suite (issue 9): builds the models, preprocesses them with timing and
# peak memory, measures every surface and setting with prt-accuracy (CPU, ground truth) and
# prt-bench (rays/s by kind; CUDA with --gpu), and writes OUT_DIR/results.{json,csv}, pareto.png and
# RESULTS.md. Everything is in suite.py; this wrapper only finds python3.
#   scripts/suite/run.sh [--quick] [--gpu] [--bin DIR] [--publish] OUT_DIR
# --help lists every option with its default.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
exec python3 "$here/suite.py" "$@"
