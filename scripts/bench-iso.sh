#!/usr/bin/env bash
# Benchmarks prt-iso (issue 5, thesis ch. 4, Implicit Surface Octrees) on the CPU: the build time of
# a POINTS-point prt-synth model (default: a 1M-point sphere; target <= 10 s on a 2-core machine)
# with the radius of influence from prt-iso's own k-NN and from prt-radii; bytes per leaf (target
# <= 56 for the leaf records) and per point; leaf counts over levels of detail (thesis 4.6, min =
# max level); and, when iso-bench is built, primary rays/s of the core on the CPU with quantized
# and float leaves and the hit error against the analytic sphere. Builds nothing: it runs the
# binaries of an existing build.
#
# Usage: scripts/bench-iso.sh BUILD_DIR [POINTS]
#   BUILD_DIR  a configured and built tree with bin/prt-synth and bin/prt-iso (optional: bin/prt-radii,
#              bin/iso-bench): make prt-synth prt-iso prt-radii iso-bench
#   POINTS     points of the synthetic sphere (default 1000000)
# Environment: REPEAT (default 3) timed builds per configuration (median wall time reported, with
#   the CPU seconds of that run), SHAPE (default sphere; any prt-synth shape), LEVELS (default
#   "4 5 6 7 8 9"), THREADS (default 0 = all), OUT (folder for the pools and JSON; default a
#   temporary folder, removed unless KEEP=1).
# Wall times count the time the build waits for a core on a shared machine: the load average is
# printed with the results, and the CPU seconds (user + sys) do not depend on it.
set -euo pipefail
# shellcheck source=lib/bench-common.sh
. "$(dirname "$0")/lib/bench-common.sh"
bench_args "$@"
points=${2:-1000000}
repeat=${REPEAT:-3}
shape=${SHAPE:-sphere}
levels=${LEVELS:-"4 5 6 7 8 9"}
threads=${THREADS:-0}
bin=$build/bin
bench_need bench-iso "$build" "prt-synth prt-iso prt-radii iso-bench" "$bin/prt-synth" "$bin/prt-iso"
command -v python3 >/dev/null || { echo "bench-iso: python3 is needed to tabulate the JSON results" >&2; exit 1; }
[ -x /usr/bin/time ] || { echo "bench-iso: /usr/bin/time (Debian package 'time') is needed for CPU seconds" >&2; exit 1; }

bench_workdir bench-iso "${OUT:-}"

echo "# prt-iso (Implicit Surface Octree, thesis ch. 4): $shape of $points points, median of $repeat builds"
echo "# machine: $(nproc) cores, $(uname -m), $(bench_cpu_model), $(free -g | awk '/Mem:/ {print $2}') GiB"
echo "# load average before: $(bench_load)"
echo "# results (pools, JSON): $work"
echo

"$bin/prt-synth" "$shape" -o "$work/model.pool" -n "$points" --quiet

# iso_build TAG INPUT ARGS...: REPEAT builds of INPUT into $work/TAG.pool; keeps the stats JSON of
# the median-wall run as $work/TAG.json and appends "wall cpu maxrss" to it.
iso_build() {
    local tag=$1 input=$2
    shift 2
    local runs=()
    for r in $(seq 1 "$repeat"); do
        /usr/bin/time -f "%e %U %S %M" -o "$work/$tag.time.$r" \
            "$bin/prt-iso" "$input" -o "$work/$tag.pool" --quiet -j "$threads" --stats-json "$work/$tag.$r.json" "$@"
        runs+=("$(cat "$work/$tag.time.$r") $r")
    done
    local median
    median=$(printf '%s\n' "${runs[@]}" | sort -n | sed -n "$(( (repeat + 1) / 2 ))p")
    local r=${median##* }
    python3 - "$work/$tag.$r.json" "$work/$tag.json" "$median" <<'EOF'
import json, sys
j = json.load(open(sys.argv[1]))
wall, user, sys_s, rss, _ = sys.argv[3].split()
j["wall"] = float(wall); j["cpu"] = float(user) + float(sys_s); j["maxrss_mb"] = int(rss) / 1024
json.dump(j, open(sys.argv[2], "w"), indent=2)
EOF
}

configs=()
iso_build knn "$work/model.pool"
configs+=(knn)
iso_build knn_both "$work/model.pool" --storage both
configs+=(knn_both)
if [ -x "$bin/prt-radii" ]; then
    /usr/bin/time -f "%e %U %S" -o "$work/radii.time" "$bin/prt-radii" "$work/model.pool" -o "$work/model_radii.pool" --quiet
    read -r radii_wall radii_user radii_sys < "$work/radii.time"
    iso_build radii "$work/model_radii.pool"
    configs+=(radii)
else
    echo "bench-iso: $bin/prt-radii not built (FLANN): skipping the radii-section build" >&2
fi

echo "## Build (all levels adaptive: --max-level 10, X = 2)"
echo
python3 - "$work" "${configs[@]}" <<'EOF'
import json, sys
work = sys.argv[1]
print("| radii | storage | wall s | CPU s | peak MB | filled leaves (active + passive + closure - uncrossed) | nodes | bytes/leaf: record | ISO total | ISO bytes/point | radii / tree / passive / balance / corners / closure / encode s |")
print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
for tag in sys.argv[2:]:
    j = json.load(open(f"{work}/{tag}.json"))
    p = j["parameters"]
    leaves = j["leaves"]
    record = 56 if p["storage"] == "q8" else (160 if p["storage"] == "f32" else 216)
    print(f"| {p['radius_used']} | {p['storage']} | {j['wall']:.2f} | {j['cpu']:.2f} | {j['maxrss_mb']:.0f} | "
          f"{leaves} ({j['active_leaves']} + {j['passive_leaves']} + {j['closure_leaves']} - {j['uncrossed_leaves']}) | {j['nodes']} | "
          f"{record} | {j['iso_bytes_per_leaf']:.1f} | {j['iso_bytes'] / j['points']:.1f} | "
          f"{j['seconds_radii']:.2f} / {j['seconds_tree']:.2f} / {j['seconds_passive']:.2f} / {j['seconds_balance']:.2f} / "
          f"{j['seconds_corners']:.2f} / {j['seconds_closure']:.2f} / {j['seconds_encode']:.2f} |")
j = json.load(open(f"{work}/knn.json"))
print()
print(f"corners: {j['corners']} distinct for {j['corner_slots']} corner slots ({j['corner_slots'] / max(j['corners'], 1):.2f} leaves share a corner on average), "
      f"{j['mean_neighbours']:.1f} points counted per corner, {j['far_corners']} beyond every support")
# corner sharing instead of replication (thesis 4.4): 8 x 4-byte indices per leaf + 7 bytes per distinct corner
shared = 32 + 7 * j["corners"] / max(j["leaves"], 1)
print(f"corner sharing instead of replication would store {shared:.1f} bytes per leaf (8 indices + 7 B per distinct corner) "
      f"against 56: {100 * (1 - shared / 56):.0f}% less, for 8 scattered reads per leaf instead of one 56-byte record")
EOF
if [ -n "${radii_wall:-}" ]; then
    echo
    echo "prt-radii (FLANN, k = 9) before the radii-section build: ${radii_wall} s wall, $(python3 -c "print(round($radii_user + $radii_sys, 2))") s CPU"
fi

echo
echo "## Levels of detail (thesis 4.6: --min-level L --max-level L, k-NN radii, q8)"
echo
lod=()
for l in $levels; do
    iso_build "lod$l" "$work/model.pool" --min-level "$l" --max-level "$l"
    lod+=("lod$l")
done
python3 - "$work" "${lod[@]}" <<'EOF'
import json, sys
work = sys.argv[1]
print("| level | filled leaves | passive | closure | far corners | nodes | ISO MB | bytes/leaf | wall s | CPU s |")
print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
for tag in sys.argv[2:]:
    j = json.load(open(f"{work}/{tag}.json"))
    print(f"| {j['parameters']['max_level']} | {j['leaves']} | {j['passive_leaves']} | {j['closure_leaves']} | {j['far_corners']} | {j['nodes']} | "
          f"{j['iso_bytes'] / 1e6:.2f} | {j['iso_bytes_per_leaf']:.1f} | {j['wall']:.2f} | {j['cpu']:.2f} |")
EOF

if [ -x "$bin/iso-bench" ]; then
    echo
    echo "## Ray tracing on the CPU (iso-bench: 512x512 primary rays, all cores, IsoParams defaults)"
    echo
    "$bin/iso-bench" "$work/knn_both.pool" --repeat 3 -j "$threads" --json "$work/rays.json"
    for l in $levels; do
        "$bin/iso-bench" "$work/lod$l.pool" --repeat 1 -j "$threads" | tail -n 1 | sed "s/^q8 /L$l q8/"
    done
else
    echo "bench-iso: $bin/iso-bench not built: skipping the ray tracing numbers" >&2
fi
echo
echo "# load average after: $(bench_load)"
