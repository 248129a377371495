#!/usr/bin/env bash
# Benchmarks the splat pipeline (issue 3, thesis 3.1-3.4): prt-radii (k-NN radii) and prt-octree
# (octree build with replication) on a synthetic sphere of POINTS points, then an octree sweep over
# the leaf size X for both split rules (overlaps: X bounds the splats per leaf, replicas included;
# centres: X bounds the centres per leaf, thesis 3.2 after [LMR07]). Builds nothing: it runs the
# binaries of an existing build.
#
# Usage: scripts/bench-splat.sh BUILD_DIR [POINTS] [REPEAT]
#   BUILD_DIR  a configured and built tree: bin/prt-radii, bin/prt-octree, and bin/prt-synth or
#              tests/preprocess/splat/splat-bench-gen (make prt-radii prt-octree prt-synth)
#   POINTS     points of the model (default 1000000)
#   REPEAT     timed runs of the two tools at their defaults (default 3); the table shows median
#              and min wall time (process start, pool read, work, atomic pool write with fsync)
# Environment: SWEEP_OVERLAPS (default "16 24 32 48"), SWEEP_CENTRES (default "10 16 24 32 48"),
#   SWEEP_REPEAT (runs per sweep row, the fastest is shown; default 1), THREADS (default 0 = all
#   cores), KEEP=1 keeps the work folder.
# X = 10 with the overlaps rule is left out of the default sweep: it is below the ~10-fold overlap
# of k = 9 disks, so the tree stops only at the --min-cell limit (measured on a 1M random sphere:
# 182 stored splats per point, 6 KB per point, 12 GB of memory).
set -euo pipefail
# shellcheck source=lib/bench-common.sh
. "$(dirname "$0")/lib/bench-common.sh"
bench_args "$@"
points=${2:-1000000}
repeat=${3:-3}
threads=${THREADS:-0}
sweep_overlaps=${SWEEP_OVERLAPS:-16 24 32 48}
sweep_centres=${SWEEP_CENTRES:-10 16 24 32 48}
sweep_repeat=${SWEEP_REPEAT:-1}
radii=$build/bin/prt-radii
octree=$build/bin/prt-octree
bench_need bench-splat "$build" "prt-radii prt-octree" "$radii" "$octree"

bench_workdir bench-splat

# -- the model ------------------------------------------------------------------------------------
if [ -x "$build/bin/prt-synth" ]; then
    generator="prt-synth sphere (random sampling)"
    "$build/bin/prt-synth" sphere -o "$work/model.pool" -n "$points" --sampling random --quiet
elif [ -x "$build/tests/preprocess/splat/splat-bench-gen" ]; then
    generator="splat-bench-gen (random sphere)"
    "$build/tests/preprocess/splat/splat-bench-gen" "$work/model.pool" -n "$points" --quiet
else
    echo "bench-splat: no model generator: build prt-synth or splat-bench-gen" >&2
    exit 1
fi

json_number() {  # json_number FILE KEY: the first number stored under "KEY"
    sed -n "s/^ *\"$2\": *\([-0-9.eE+]*\).*/\1/p" "$1" | head -1
}

# timed TOOL ARGS...: runs REPEAT times after one warm-up; prints "median min" wall seconds
timed() {
    "$@" --quiet
    local times=() t0 t1
    for _ in $(seq "$repeat"); do
        t0=$(date +%s.%N)
        "$@" --quiet
        t1=$(date +%s.%N)
        times+=("$(awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.3f", b - a }')")
    done
    local sorted
    sorted=$(printf '%s\n' "${times[@]}" | sort -g)
    echo "$(echo "$sorted" | sed -n "$(( (repeat + 1) / 2 ))p") $(echo "$sorted" | head -1)"
}

echo "# splat pipeline, $points points, model: $generator, threads: $threads"
echo "# machine: $(nproc) cores, $(uname -m), $(bench_cpu_model), load average $(bench_load)"
echo
printf '%-34s %9s %9s %s\n' "step (defaults)" "median s" "min s" "notes"
read -r med min < <(timed "$radii" "$work/model.pool" -o "$work/radii.pool" -j "$threads" --stats-json "$work/radii.json")
printf '%-34s %9s %9s %s\n' "prt-radii (k = 9)" "$med" "$min" \
    "$(printf 'index %.3f s, search %.3f s, clamped %s, median radius %.4g' "$(json_number "$work/radii.json" index_seconds)" \
        "$(json_number "$work/radii.json" search_seconds)" "$(json_number "$work/radii.json" clamped)" \
        "$(json_number "$work/radii.json" median)")"
read -r med min < <(timed "$octree" "$work/radii.pool" -o "$work/octree.pool" -j "$threads" --stats-json "$work/octree.json")
printf '%-34s %9s %9s %s\n' "prt-octree (X = 16, overlaps)" "$med" "$min" \
    "$(printf 'build %.3f s, replication %.2f, %.1f B/point' "$(json_number "$work/octree.json" build_seconds)" \
        "$(json_number "$work/octree.json" replication_factor)" "$(json_number "$work/octree.json" pool_bytes_per_point)")"
rm -f "$work/octree.pool"

echo
printf '%-9s %5s %9s %9s %6s %10s %8s %9s %10s %10s\n' "split by" "X" "build s" "total s" "depth" "nodes" "leaves" "max/leaf" "replicas" "B/point"
sweep() {  # sweep RULE X: SWEEP_REPEAT runs, the fastest one's times
    local j=$work/sweep.json build_min="" total_min=""
    for _ in $(seq "$sweep_repeat"); do
        "$octree" "$work/radii.pool" -o "$work/sweep.pool" -X "$2" --split-by "$1" -j "$threads" --stats-json "$j" --quiet
        build_min=$(awk -v a="$build_min" -v b="$(json_number "$j" build_seconds)" 'BEGIN { print (a == "" || b < a) ? b : a }')
        total_min=$(awk -v a="$total_min" -v b="$(json_number "$j" total_seconds)" 'BEGIN { print (a == "" || b < a) ? b : a }')
    done
    printf '%-9s %5s %9.3f %9.3f %6s %10s %8s %9s %10.2f %10.1f\n' "$1" "$2" \
        "$build_min" "$total_min" "$(json_number "$j" depth)" \
        "$(json_number "$j" nodes)" "$(json_number "$j" filled_leaves)" "$(json_number "$j" max_leaf_splats)" \
        "$(json_number "$j" replication_factor)" "$(json_number "$j" pool_bytes_per_point)"
    rm -f "$work/sweep.pool"
}
for x in $sweep_overlaps; do sweep overlaps "$x"; done
for x in $sweep_centres; do sweep centres "$x"; done
echo
echo "# build s: octree build in the tool; total s: whole tool run including pool read and write"
echo "# (fastest of $sweep_repeat)."
echo "# leaves: filled leaves; max/leaf: most splats in one leaf; replicas: stored / unique splats;"
echo "# B/point: output pool bytes per input point (positions, normals, radii and octree)."
