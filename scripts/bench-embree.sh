#!/usr/bin/env bash
# CPU peer benchmark: PointRT's CPU backend against Embree 3 on the same splats and the same view,
# in one run (preprocess/bench/prt_bench_embree.cpp). The scene is prt-bench's: the synthetic room of
# POINTS points seen from inside, one light; scenarios primary, shadow (one shadow light) and
# reflect4 (4 mirror bounces). Ours traces the replicated octree with splat blending (thesis 2-3);
# Embree traces one oriented disc per point (rtcIntersect1, with the seamless front/back rule of
# thesis 3.6 as an intersection filter); shading and secondary rays are the same core functions.
# Prints both frame times and rays per second and the ratio ours / Embree (> 1: ours is faster).
#
# Usage: scripts/bench-embree.sh BUILD_DIR [POINTS] [SIZE] [FRAMES]
#   BUILD_DIR  a configured tree with Embree found (Debian: apt-get install libembree-dev); the
#              script builds its target prt-bench-embree there
#   POINTS     points of the synthetic room (default 1000000)
#   SIZE       image width and height (default 512)
#   FRAMES     timed frames per scenario and renderer, the median is reported (default 3)
# Environment: THREADS (default 0 = all cores, the same for both), JSON=FILE writes the results,
#   JOBS (build jobs, default: all cores), EXTRA (more prt-bench-embree arguments, e.g.
#   "--scenarios primary,shadow" or "--max-leaf 64"), CULLED=1: ours traces the room after prt-cull
#   (the default chain's octree: prt-bench --save-pool, then prt-cull with its defaults) with the
#   same camera and light (preprocess/bench/bench_room.json), Embree the same points.
# The two renderers draw their frames in turns (ours, Embree, ours, ...) and ours / Embree is the
# median over those frame pairs, so a shared machine's changing speed moves both alike.
set -euo pipefail
# shellcheck source=lib/bench-common.sh
. "$(dirname "$0")/lib/bench-common.sh"
bench_args "$@"
points=${2:-1000000}
size=${3:-512}
frames=${4:-3}
if ! cmake --build "$build" -j "${JOBS:-$(nproc)}" --target prt-bench-embree >/dev/null 2>&1; then
    echo "bench-embree: cannot build prt-bench-embree in $build: is Embree 3 installed (libembree-dev) and" \
         "found by CMake (PRT_WITH_EMBREE)? See the configure log." >&2
    exit 1
fi
echo "# machine: $(nproc) cores, $(bench_cpu_model), load average $(bench_load)"
args=(--width "$size" --height "$size" --frames "$frames" --warmup 1 --threads "${THREADS:-0}" --quiet)
if [ "${CULLED:-0}" = 1 ]; then
    cmake --build "$build" -j "${JOBS:-$(nproc)}" --target prt-bench prt-cull >/dev/null
    bench_workdir bench-embree
    "$build/bin/prt-bench" --backend cpu --synthetic "$points" --save-pool "$work/room.pool" --frames 1 --warmup 0 \
        --width 16 --height 16 --scenarios primary --quiet >/dev/null
    "$build/bin/prt-cull" "$work/room.pool" -o "$work/room_c.pool" --quiet
    sed 's/"room.pool"/"room_c.pool"/' "$(dirname "$0")/../preprocess/bench/bench_room.json" >"$work/scene.json"
    args+=("$work/room_c.pool" --scene "$work/scene.json")
else
    args+=(--synthetic "$points")
fi
[ -n "${JSON:-}" ] && args+=(--json "$JSON")
# shellcheck disable=SC2086
"$build/bin/prt-bench-embree" "${args[@]}" ${EXTRA:-}
