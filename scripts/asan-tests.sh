#!/usr/bin/env bash
# Builds PointRT with AddressSanitizer + UndefinedBehaviorSanitizer (-DPRT_SANITIZE=ON, no CUDA)
# into BUILD_DIR and runs the CPU test suite under them, less the tests labelled slow (ctest -L cpu
# -LE slow: end-to-end runs over 20 s whose tools faster tests also run; tests/CMakeLists.txt).
# Prints how long the build and the tests took. Any sanitizer report fails the test that triggered
# it (UBSan is not recoverable in this build; ASan aborts; LeakSanitizer reports make the process
# exit non-zero).
# Installs nothing: g++ from scripts/install-deps.sh brings libasan and libubsan (Debian's
# libgcc-12-dev depends on them); clang and libFuzzer are for scripts/fuzz.sh only. Run by .ci/run
# after the README's test command.
#
# Usage: scripts/asan-tests.sh [--clean] [ctest arguments...]
#   --clean    remove BUILD_DIR first (a clean build, as CI would do)
# Environment: BUILD_DIR (default: build-asan at the repository root), JOBS (default: nproc),
#   CMAKE_ARGS (extra configure arguments, e.g. "-DPRT_WITH_PCL=OFF").
set -euo pipefail
if [ "${1:-}" = "-h" ] || [ "${1:-}" = "--help" ]; then
    sed -n '2,15p' "$0" | sed 's/^# \{0,1\}//'
    exit 0
fi
root=$(cd "$(dirname "$0")/.." && pwd)
build=${BUILD_DIR:-$root/build-asan}
jobs=${JOBS:-$(nproc)}
if [ "${1:-}" = "--clean" ]; then
    rm -rf "$build"
    shift
fi

# detect_leaks: LeakSanitizer (on by default with ASan on Linux, stated for clarity);
# abort_on_error: a core-like abort the test runner reports; strict_string_checks and
# detect_stack_use_after_return catch more at a small cost. halt_on_error for UBSan is already
# implied by -fno-sanitize-recover=undefined.
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1:strict_string_checks=1:detect_stack_use_after_return=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}

start=$(date +%s)
mkdir -p "$build"
# g++, the compiler scripts/build.sh gets on Debian, unless CC/CXX say otherwise.
export CC=${CC:-gcc} CXX=${CXX:-g++}
# -O1 -g1: the optimisation level AddressSanitizer's documentation suggests, with line tables for
# the reports' stack traces. Measured on the 2-core dev machine (formats/src/tool.cpp, ASan+UBSan):
# -O2 -g 94 s, -O2 -g1 67 s, -O1 -g1 40 s; a full -O2 -g build took 46 min of CI's 90.
# shellcheck disable=SC2086 # CMAKE_ARGS holds several arguments
# No GPU-labelled test programs, no benchmark programs that no test runs and no Embree peer
# benchmark: the stage runs -L cpu, and those took 305 s of its 2450 s of compiling (2026-12-02).
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPRT_SANITIZE=ON -DPRT_WITH_CUDA=OFF \
    -DPRT_BUILD_GPU_TESTS=OFF -DPRT_BUILD_BENCHMARKS=OFF -DPRT_WITH_EMBREE=OFF \
    "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG" "-DCMAKE_C_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG" \
    ${CMAKE_ARGS:-} >"$build/asan-configure.log" 2>&1 || { cat "$build/asan-configure.log" >&2; exit 1; }
cmake --build "$build" -j "$jobs" >"$build/asan-build.log" 2>&1 ||
    { tail -50 "$build/asan-build.log" >&2; echo "asan-tests: build failed (log: $build/asan-build.log)" >&2; exit 1; }
built=$(date +%s)
echo "asan-tests: configure + build: $((built - start)) s ($jobs jobs, $(nproc) cores; log: $build/asan-build.log)"

# Two passes. The window tests (prt-play under Xvfb) load the system's OpenGL driver with
# dlopen and unload it before LeakSanitizer runs at exit; the driver's own allocations are then
# reported as leaks from "<unknown module>", which no suppression can name. They run with leak
# detection off (ASan and UBSan stay on); every other test runs with it on. Window tests are the
# GoogleTest suites whose names end in WindowTest (WindowTest, BrickStreamWindowTest, ...).
status=0
(cd "$build" && ctest -L cpu -LE slow -E '^[A-Za-z]*WindowTest[.]' --output-on-failure -j "$jobs" "$@") || status=$?
(cd "$build" && ASAN_OPTIONS="$ASAN_OPTIONS:detect_leaks=0" \
    ctest -L cpu -LE slow -R '^[A-Za-z]*WindowTest[.]' --output-on-failure -j "$jobs" "$@") || status=$?
done_at=$(date +%s)
echo "asan-tests: ctest -L cpu -LE slow: $((done_at - built)) s; total $((done_at - start)) s"
exit $status
