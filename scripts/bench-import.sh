#!/usr/bin/env bash
# Benchmarks PLY import (issue 2): a generated binary little-endian PLY with normals (default 1M
# points), read by our reader, by PCL's pcl::PLYReader and by OpenMesh's reader (those two when the
# build has them), plus the whole prt-import tool end to end (process start, read, clean, pool
# write with fsync). Builds nothing: it runs the binaries of an existing build.
#
# Usage: scripts/bench-import.sh BUILD_DIR [POINTS] [REPEAT]
#   BUILD_DIR  a configured and built tree (needs bin/prt-bench-import and bin/prt-import:
#              make prt-bench-import prt-import)
#   POINTS     points in the generated file (default 1000000)
#   REPEAT     timed runs per reader after one warm-up (default 5); the table shows median and min
set -euo pipefail
# shellcheck source=lib/bench-common.sh
. "$(dirname "$0")/lib/bench-common.sh"
bench_args "$@"
points=${2:-1000000}
repeat=${3:-5}
bench=$build/bin/prt-bench-import
tool=$build/bin/prt-import
bench_need bench-import "$build" "prt-bench-import prt-import" "$bench" "$tool"

work=$(mktemp -d "${TMPDIR:-/tmp}/prt-bench-import.XXXXXX")
trap 'rm -rf "$work"' EXIT
ply=$work/points.ply

echo "# PLY import, $points points (binary_little_endian, float x y z nx ny nz), $repeat runs"
echo "# machine: $(nproc) cores, $(uname -m), $(bench_cpu_model)"
"$bench" --points "$points" --file "$ply" --repeat "$repeat" --quiet

# The tool end to end, as a user runs it (one warm-up, then REPEAT runs; wall clock).
"$tool" "$ply" -o "$work/out.pool" --quiet
times=()
for _ in $(seq "$repeat"); do
    t0=$(date +%s.%N)
    "$tool" "$ply" -o "$work/out.pool" --quiet
    t1=$(date +%s.%N)
    times+=("$(awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.6f", b - a }')")
done
sorted=$(printf '%s\n' "${times[@]}" | sort -g)
median=$(echo "$sorted" | sed -n "$(( (repeat + 2) / 2 ))p")
min=$(echo "$sorted" | head -1)
printf '%-30s %10.3f %10.3f %10s\n' "prt-import tool (end to end)" "$median" "$min" "$points"
