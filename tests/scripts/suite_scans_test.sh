#!/usr/bin/env bash
# Tests scripts/suite/suite.py's real-scan path (issue 9) against the tools of a build: the scans
# imported once with --import-scans, a run on those pools with --scan-pools (what the GPU machine,
# which lacks PCL and OpenMesh, does), the kitten's rows in RESULTS.md, and a run cut short by
# SIGTERM still writing its reports.
# Usage: suite_scans_test.sh SUITE_PY BIN_DIR SHARED_DATA   (exit 77 = skipped)
set -uo pipefail
suite=$1
bin=$(cd "$2" && pwd)
export PRT_SHARED_DATA_DIR=$3
for t in prt-import prt-radii prt-octree prt-mls prt-iso prt-info prt-accuracy; do
    if [ ! -x "$bin/$t" ]; then
        echo "SKIP: $t not built in $bin"
        exit 77
    fi
done
if [ ! -f "$PRT_SHARED_DATA_DIR/points/cgal_kitten/kitten.xyz" ]; then
    echo "SKIP: $PRT_SHARED_DATA_DIR/points/cgal_kitten/kitten.xyz absent (real data folder not here)"
    exit 77
fi

name=suite_scans_test
# shellcheck source=check_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/check_lib.sh"

python3 "$suite" --import-scans "$work/pools" --scans kitten --bin "$bin" 2>"$work/import.log"
check "--import-scans exits 0" test $? = 0
check "--import-scans writes kitten.pool" "$bin/prt-info" "$work/pools/kitten.pool"
check "--import-scans imports only what --scans names" test ! -e "$work/pools/bunny.pool"

python3 "$suite" "$work/run" --quick --shapes none --fidelity none --scans kitten --scan-pools "$work/pools" --no-bench \
    --bin "$bin" --quiet
check "a scans-only run exits 0" test $? = 0
check "RESULTS.md has the kitten's MLS rows" contains "$work/run/RESULTS.md" "| kitten | mls | k4 |"
check "RESULTS.md has the kitten's ISO rows" contains "$work/run/RESULTS.md" "| kitten | iso | L8_q8_r0 |"
check "results.json lists no failure" python3 -c "import json,sys; sys.exit(len(json.load(open('$work/run/results.json'))['failures']))"

# SIGTERM once the run has started (its output folder made, its handler installed just after),
# not after a fixed second: on a loaded machine Python's start-up alone can take that long.
python3 "$suite" "$work/cut" --quick --shapes none --fidelity none --scans kitten \
    --scan-pools "$work/pools" --no-bench --bin "$bin" --quiet &
cut_pid=$!
for _ in $(seq 600); do [ -d "$work/cut/runs" ] && break; sleep 0.1; done
sleep 1
kill -TERM $cut_pid
wait $cut_pid
check "a run cut by SIGTERM still writes RESULTS.md" test -s "$work/cut/RESULTS.md"
check "and names the interruption" contains "$work/cut/RESULTS.md" "interrupted (signal 15)"

missing=$(python3 "$suite" "$work/none" --quick --shapes none --fidelity none --scans kitten --scan-pools "$work/empty" \
    --no-bench --bin "$bin" 2>&1)
check "a scan missing from --scan-pools is skipped with a message" \
    grep -q "kitten: not in $work/empty, skipped" <<<"$missing"

finish_checks
