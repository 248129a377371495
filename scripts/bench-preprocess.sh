#!/usr/bin/env bash
# Benchmarks the preprocessing chain of a splat and ISO pool (issue 19: "preprocessing scales with
# cores"): a generated binary PLY of POINTS points with normals is imported and run through
# prt-import -> prt-radii -> prt-octree -> prt-cull -> prt-iso (CPU backends unless BACKEND), each
# step a separate tool reading the previous step's pool, as a user runs them. Every thread count of
# THREADS runs the whole chain pinned to that many cores (taskset: the tools use the cores they are given), REPEAT
# times; the table shows each step's fastest wall time (process start, read, work, atomic write with
# fsync) and the speedup of the largest count over the smallest. Builds nothing: it runs the binaries
# of an existing build.
#
# The model: a closed room (a 1 x 1 x 1 box seen from inside, normals inward) with a sphere of
# radius 0.2 on its floor (normals outward), points uniform by area (Python's random, seed 1): the surfaces of
# prt-synth's room without its cube, written as a PLY file so that prt-import parses a file.
#
# Usage: scripts/bench-preprocess.sh BUILD_DIR [POINTS] [THREADS] [REPEAT]
#   BUILD_DIR  a configured and built tree (make prt-import prt-radii prt-octree prt-cull prt-iso)
#   POINTS     points in the generated file (default 1000000)
#   THREADS    thread counts, comma separated (default "1,2,N" with N the cores this process has)
#   REPEAT     runs of the chain per thread count; the fastest counts (default 2)
# Environment: KEEP=1 keeps the work folder (its path is printed); BACKEND=auto|cpu|cuda is
#   prt-radii's and prt-cull's --backend (CULL_BACKEND, its older name, still works) (default cpu:
#   the chain on the cores alone; auto is what a user on a GPU
#   machine gets); FRESH=1 removes each step's output of the previous run before timing the step
#   (default 0: every run after the first writes over it, as in every measurement before
#   2026-12-06, and pays for the old file's removal in its rename: 0.04 s for 150 MB on the H100
#   host's ext4, preprocess/bench/results/h100-2026-12-06-issue19-chain-close/).
set -euo pipefail
# shellcheck source=lib/bench-common.sh
. "$(dirname "$0")/lib/bench-common.sh"
bench_args "$@"
points=${2:-1000000}
cores=$(nproc)
threads=${3:-$(printf '1\n2\n%s\n' "$cores" | sort -nu | paste -sd,)}
repeat=${4:-2}
cull_backend=${BACKEND:-${CULL_BACKEND:-cpu}}
fresh=${FRESH:-0}
case $fresh in 0 | 1) ;; *)
    echo "bench-preprocess: FRESH must be 0 or 1, not '$fresh'" >&2
    exit 1
    ;;
esac
case $cull_backend in auto | cpu | cuda) ;; *)
    echo "bench-preprocess: BACKEND must be auto, cpu or cuda, not '$cull_backend'" >&2
    exit 1
    ;;
esac
steps="prt-import prt-radii prt-octree prt-cull prt-iso"
bins=()
for s in $steps; do bins+=("$build/bin/$s"); done
bench_need bench-preprocess "$build" "$steps" "${bins[@]}"
command -v taskset >/dev/null || { echo "bench-preprocess: taskset is missing (util-linux)" >&2; exit 1; }
bench_workdir bench-preprocess
[ "${KEEP:-0}" = 1 ] && echo "# work folder: $work"

python3 - "$work/room.ply" "$points" <<'EOF'
import math, random, sys
from array import array
path, n = sys.argv[1], int(sys.argv[2])
rng = random.Random(1)
r = 0.2
areas = [1.0] * 6 + [4 * math.pi * r * r]
count = [int(n * a / sum(areas)) for a in areas]
count[-1] += n - sum(count)
v = array("f")
for face in range(6):  # box faces, normals inward
    axis, side = face // 2, (-0.5, 0.5)[face % 2]
    for _ in range(count[face]):
        p = [rng.uniform(-0.5, 0.5) for _ in range(3)]
        q = [0.0, 0.0, 0.0]
        p[axis], q[axis] = side, -math.copysign(1.0, side)
        v.extend(p + q)
for _ in range(count[6]):  # the sphere, normals outward
    d = [rng.gauss(0.0, 1.0) for _ in range(3)]
    length = math.sqrt(sum(c * c for c in d)) or 1.0
    d = [c / length for c in d]
    v.extend([d[0] * r, d[1] * r - 0.5 + r, d[2] * r] + d)
if sys.byteorder != "little":
    v.byteswap()
with open(path, "wb") as f:
    f.write((f"ply\nformat binary_little_endian 1.0\nelement vertex {n}\n"
             "property float x\nproperty float y\nproperty float z\n"
             "property float nx\nproperty float ny\nproperty float nz\nend_header\n").encode())
    v.tofile(f)
EOF

echo "# preprocessing chain, $points points (room PLY with normals), fastest of $repeat runs per step; prt-radii and prt-cull --backend $cull_backend$([ "$fresh" = 1 ] && echo "; each run into a new file")"
echo "# machine: $cores cores, $(uname -m), $(bench_cpu_model); load $(bench_load)"
declare -A best
IFS=, read -r -a counts <<<"$threads"
for t in "${counts[@]}"; do
    if [ "$t" -gt "$cores" ]; then
        echo "bench-preprocess: $t threads asked for, this process has $cores cores" >&2
        exit 1
    fi
    for _ in $(seq "$repeat"); do
        in=$work/room.ply
        for s in $steps; do
            out=$work/$s.pool
            extra=()
            [ "$s" = prt-cull ] || [ "$s" = prt-radii ] && extra=(--backend "$cull_backend")
            [ "$fresh" = 1 ] && rm -f "$out"  # untimed
            t0=$(date +%s.%N)
            taskset -c "0-$((t - 1))" "$build/bin/$s" "$in" -o "$out" --quiet "${extra[@]}"
            t1=$(date +%s.%N)
            sec=$(awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.3f", b - a }')
            key="$s,$t"
            if [ -z "${best[$key]:-}" ] || awk -v a="$sec" -v b="${best[$key]}" 'BEGIN { exit !(a < b) }'; then
                best[$key]=$sec
            fi
            in=$out
        done
    done
done

lo=${counts[0]}
hi=${counts[${#counts[@]}-1]}
printf '%-12s' "step"
for t in "${counts[@]}"; do printf ' %10s' "$t thr (s)"; done
printf ' %10s\n' "${lo}->${hi}"
for row in $steps total; do
    printf '%-12s' "$row"
    for t in "${counts[@]}"; do
        if [ "$row" = total ]; then
            sum=0
            for s in $steps; do sum=$(awk -v a="$sum" -v b="${best[$s,$t]}" 'BEGIN { printf "%.3f", a + b }'); done
            best[total,$t]=$sum
        fi
        printf ' %10s' "${best[$row,$t]}"
    done
    awk -v a="${best[$row,$lo]}" -v b="${best[$row,$hi]}" 'BEGIN { printf " %9.2fx\n", a / b }'
done
