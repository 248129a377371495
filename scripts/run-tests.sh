#!/usr/bin/env bash
# Builds PointRT (if needed) and runs the test suite with CTest. GPU-labelled tests skip with a
# message where no GPU exists; tests that read ../shared/data skip where it is absent.
# Usage: scripts/run-tests.sh [ctest arguments...]   e.g. -L cpu, -LE slow
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${BUILD_DIR:-$root/build}
"$root/scripts/build.sh"
cd "$build"
ctest --output-on-failure -j "${JOBS:-$(nproc)}" "$@"
