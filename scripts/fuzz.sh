#!/usr/bin/env bash
# Fuzzes every reader with libFuzzer (issue 10): builds the fuzz targets with clang into BUILD_DIR
# (-DPRT_FUZZ=ON: ASan + UBSan + coverage), generates the seed corpus, runs each target for a fixed
# time, and prints executions, coverage and findings per target. Not part of every CI run.
#
# Usage: scripts/fuzz.sh [options] [TARGET...]
#   TARGET             ply pcd xyz obj off ply-mesh scene pool patches (default: all of them)
#   -t, --time SECONDS time per target (default 60)
#   -b, --build DIR    build folder (default: build-fuzz at the repository root)
#   -j, --jobs N       compile jobs (default: $JOBS, else 2)
#   --no-build         use the binaries already in DIR/bin
#   --fresh            start each corpus from the seeds only (default: keep growing DIR/fuzz/corpus)
#   -h, --help         this text
# Environment: FUZZ_ARGS adds libFuzzer flags to every run (e.g. "-max_len=65536").
#
# Findings (crash-*, leak-*, timeout-*, oom-* inputs) are kept in DIR/fuzz/artifacts/TARGET/; each
# libFuzzer log in DIR/fuzz/logs/TARGET.log. Replay one with DIR/bin/prt-fuzz-TARGET FILE, then
# turn it into a test in tests/fuzz/regression_test.cpp. Exit status: 0 when no target found
# anything, 1 when one did, 2 for usage or build errors.
set -euo pipefail

usage() { sed -n '2,20p' "$0" | sed 's/^# \{0,1\}//'; }

root=$(cd "$(dirname "$0")/.." && pwd)
all_targets=(ply pcd xyz obj off ply-mesh scene pool patches)
seconds=60
build=$root/build-fuzz
jobs=${JOBS:-2}
do_build=1
fresh=0
targets=()
while [ $# -gt 0 ]; do
    case $1 in
        -t | --time) seconds=${2:?--time needs a value}; shift 2 ;;
        -b | --build) build=${2:?--build needs a value}; shift 2 ;;
        -j | --jobs) jobs=${2:?--jobs needs a value}; shift 2 ;;
        --no-build) do_build=0; shift ;;
        --fresh) fresh=1; shift ;;
        -h | --help) usage; exit 0 ;;
        -*) echo "fuzz.sh: unknown option $1 (see --help)" >&2; exit 2 ;;
        *) targets+=("$1"); shift ;;
    esac
done
[ ${#targets[@]} -gt 0 ] || targets=("${all_targets[@]}")
for t in "${targets[@]}"; do
    [[ " ${all_targets[*]} " == *" $t "* ]] || { echo "fuzz.sh: unknown target '$t' (${all_targets[*]})" >&2; exit 2; }
done
[[ $seconds =~ ^[0-9]+$ ]] || { echo "fuzz.sh: --time must be whole seconds" >&2; exit 2; }

if [ $do_build = 1 ]; then
    command -v clang++ >/dev/null || { echo "fuzz.sh: clang++ not found (apt-get install clang)" >&2; exit 2; }
    generator=()
    if command -v ninja >/dev/null && [ ! -f "$build/Makefile" ]; then generator=(-G Ninja); fi
    mkdir -p "$build"
    CC=clang CXX=clang++ cmake -S "$root" -B "$build" "${generator[@]}" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
        -DPRT_FUZZ=ON -DPRT_WITH_CUDA=OFF >"$build/fuzz-configure.log" 2>&1 ||
        { cat "$build/fuzz-configure.log" >&2; echo "fuzz.sh: configure failed" >&2; exit 2; }
    cmake --build "$build" -j "$jobs" --target prt-fuzz-all >"$build/fuzz-build.log" 2>&1 ||
        { tail -40 "$build/fuzz-build.log" >&2; echo "fuzz.sh: build failed (log: $build/fuzz-build.log)" >&2; exit 2; }
fi
bin=$build/bin
work=$build/fuzz
mkdir -p "$work"

# -- seed corpus: the text seeds in tests/fuzz/corpus, the binary ones generated, the SCENE.md example
seeds=$work/seeds
rm -rf "$seeds"
mkdir -p "$seeds"
"$bin/prt-fuzz-seeds" "$seeds"
for t in "${all_targets[@]}"; do
    mkdir -p "$seeds/$t"
    if [ -d "$root/tests/fuzz/corpus/$t" ]; then cp "$root/tests/fuzz/corpus/$t"/* "$seeds/$t/"; fi
done
# shellcheck disable=SC2016 # backquotes, not an expansion
sed -n '/^```json$/,/^```$/p' "$root/formats/SCENE.md" | sed '1d;$d' >"$seeds/scene/scene-md-example.json"

printf '%-9s %6s %10s %8s %6s %7s %7s %s\n' target seconds execs exec/s cov ft corpus findings
failed=0
for t in "${targets[@]}"; do
    corpus=$work/corpus/$t
    artifacts=$work/artifacts/$t
    log=$work/logs/$t.log
    [ $fresh = 1 ] && rm -rf "$corpus"
    mkdir -p "$corpus" "$artifacts" "$work/logs"
    dict=()
    [ -f "$root/tests/fuzz/dict/$t.dict" ] && dict=(-dict="$root/tests/fuzz/dict/$t.dict")
    before=$(find "$artifacts" -type f | wc -l)
    start=$SECONDS
    # -timeout: an input taking longer is a hang; -rss_limit_mb also caps single mallocs (a
    # header's claimed count must never turn into an allocation); leaks are errors.
    rc=0
    # shellcheck disable=SC2086 # FUZZ_ARGS holds several flags
    "$bin/prt-fuzz-$t" "$corpus" "$seeds/$t" "${dict[@]}" -max_total_time="$seconds" -timeout=10 \
        -rss_limit_mb=2048 -detect_leaks=1 -print_final_stats=1 -artifact_prefix="$artifacts/" \
        ${FUZZ_ARGS:-} >"$log" 2>&1 || rc=$?
    # A run that stops on a finding exits without removing its scratch folder (fuzz_entries.cpp).
    for d in /dev/shm/prt-fuzz-* "${TMPDIR:-/tmp}"/prt-fuzz-*; do
        [ -d "$d" ] && ! kill -0 "${d##*-}" 2>/dev/null && rm -rf "$d"
    done
    execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
    rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)
    last=$(grep -E '^#[0-9]+' "$log" | tail -1 || true)
    cov=$(sed -n 's/.* cov: \([0-9]*\).*/\1/p' <<<"$last")
    ft=$(sed -n 's/.* ft: \([0-9]*\).*/\1/p' <<<"$last")
    size=$(find "$corpus" -type f | wc -l)
    found=$(( $(find "$artifacts" -type f | wc -l) - before ))
    note=$found
    if [ "$rc" != 0 ] || [ "$found" != 0 ]; then
        failed=1
        note="$found (exit $rc; $(grep -m1 -E 'ERROR: |oracle violated|deadly signal|out-of-memory|timeout' "$log" | cut -c1-100))"
    fi
    printf '%-9s %6s %10s %8s %6s %7s %7s %s\n' "$t" "$((SECONDS - start))" "${execs:-?}" "${rate:-?}" "${cov:-?}" \
        "${ft:-?}" "$size" "$note"
done
echo "# logs: $work/logs; findings: $work/artifacts/TARGET/ (replay: $bin/prt-fuzz-TARGET FILE)"
exit $failed
