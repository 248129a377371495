# shellcheck shell=bash
# Shared by the scripts/bench-*.sh benchmarks (source it: . "$(dirname "$0")/lib/bench-common.sh").
# Each script keeps its own usage text in its header comment; these helpers only do what every
# script did by hand: the usage check, the check for the binaries of the build, the work folder and
# the machine line.

# bench_args ARGS...: with no argument, -h or --help, prints the calling script's header comment
# (from line 2 to the first line that is not a comment, without the leading "# ") and exits 2;
# otherwise sets the global "build" to the first argument (every script's BUILD_DIR).
bench_args() {
    if [ $# -lt 1 ] || [ "$1" = "-h" ] || [ "$1" = "--help" ]; then
        awk 'NR > 1 && !/^#/ { exit } NR > 1' "$0" | sed 's/^# \{0,1\}//'
        exit 2
    fi
    build=$1
}

# bench_need NAME BUILD TARGETS FILE...: exits 1 with "NAME: FILE is missing (build it: make -C BUILD
# TARGETS)" for the first FILE that is not an executable.
bench_need() {
    local name=$1 build=$2 targets=$3 b
    shift 3
    for b in "$@"; do
        if [ ! -x "$b" ]; then
            echo "$name: $b is missing (build it: make -C $build $targets)" >&2
            exit 1
        fi
    done
}

# bench_workdir NAME [DIR]: sets the global "work" to DIR (created when missing) or, when DIR is
# empty or absent, to a new temporary folder prt-NAME.XXXXXX that is removed on exit unless KEEP=1.
bench_workdir() {
    if [ -n "${2:-}" ]; then
        work=$2
        mkdir -p "$work"
    else
        work=$(mktemp -d "${TMPDIR:-/tmp}/prt-$1.XXXXXX")
        if [ "${KEEP:-0}" != 1 ]; then trap 'rm -rf "$work"' EXIT; fi
    fi
}

# bench_cpu_model: the processor's model name from /proc/cpuinfo.
bench_cpu_model() {
    grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'
}

# bench_load: the 1, 5 and 15 minute load averages.
bench_load() {
    cut -d' ' -f1-3 /proc/loadavg
}
