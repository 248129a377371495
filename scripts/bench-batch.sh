#!/usr/bin/env bash
# Benchmarks scripts/prt-batch on Dask (issue 21): SCANS generated XYZ scans (unit spheres with
# normals, point counts spread evenly from MIN_POINTS to MAX_POINTS) through prt-import, prt-radii
# and prt-octree, first by WORKERS independent serial pipelines (the files dealt round-robin to
# WORKERS bash loops calling the tools one after the other: the throughput a user gets by hand),
# then by prt-batch's local cluster of WORKERS worker processes, then prt-batch again over the
# same folder (every output current: the cost of a resume pass). Each step runs with one thread.
# Prints the wall times, the throughput ratio (serial pipelines' wall time / prt-batch's, 1.0 =
# equal throughput) and the overhead per task ((prt-batch - serial) x WORKERS / tasks, in
# worker-seconds: the cluster's start-up, scheduling, hashing and the final rename, spread over
# the tasks). Builds nothing: it runs the tools of an existing build.
#
# Usage: scripts/bench-batch.sh BUILD_DIR [SCANS] [MIN_POINTS] [MAX_POINTS] [WORKERS]
#   BUILD_DIR   a built tree (needs bin/prt-import, bin/prt-radii, bin/prt-octree)
#   SCANS       number of scans (default 40)
#   MIN_POINTS  points of the smallest scan (default 20000)
#   MAX_POINTS  points of the largest scan (default 100000); the issue's target: 200 scans of
#               100000 to 1000000 points on 16 cores (SCANS=200 MIN=100000 MAX=1000000 WORKERS=16)
#   WORKERS     serial pipelines and Dask workers (default: the number of cores)
# Environment: KEEP=1 keeps the work folder; TMPDIR where it goes (it holds the scans and two
# copies of the pools: about 120 bytes per point); PRT_PYTHON the Python with Dask that runs
# prt-batch and the check (default /usr/bin/python3; on a host without Dask, a bundle such as
# preprocess/bench/results/h200-2026-11-26-issue21-batch/make-python-bundle.sh makes).
set -euo pipefail
# shellcheck source=lib/bench-common.sh
. "$(dirname "$0")/lib/bench-common.sh"
bench_args "$@"
scans=${2:-40}
min_points=${3:-20000}
max_points=${4:-100000}
workers=${5:-$(nproc)}
bin=$(cd "$build/bin" && pwd)
batch=$(cd "$(dirname "$0")" && pwd)/prt-batch
py=${PRT_PYTHON:-/usr/bin/python3}
bench_need bench-batch "$build" "prt-import prt-radii prt-octree" "$bin/prt-import" "$bin/prt-radii" "$bin/prt-octree"
bench_workdir bench-batch
in=$work/scans
mkdir -p "$in" "$work/serial" "$work/dask"

echo "# prt-batch on Dask: $scans scans of $min_points..$max_points points, import,radii,octree, $workers workers x 1 thread"
echo "# machine: $(nproc) cores, $(uname -m), $(bench_cpu_model), load before: $(bench_load)"
# The scans, generated in parallel (not timed).
seq 0 $((scans - 1)) | xargs -P "$(nproc)" -I{} bash -c '
    i=$1; n=$(( $2 + ($3 - $2) * i / ($4 > 1 ? $4 - 1 : 1) ))
    awk -v n="$n" -v s="$i" "BEGIN { g = 3.14159265358979 * (3 - sqrt(5));
        for (i = 0; i < n; i++) { y = 1 - 2 * (i + 0.5) / n; r = sqrt(1 - y * y); t = g * i + 0.001 * s;
            printf \"%.7f %.7f %.7f %.7f %.7f %.7f\n\", r * cos(t), y, r * sin(t), r * cos(t), y, r * sin(t) } }" \
        >"$5/scan$(printf %04d "$i").xyz"' _ {} "$min_points" "$max_points" "$scans" "$in"
points=$(cat "$in"/*.xyz | wc -l)
echo "# $points points in all, $(du -sh "$in" | cut -f1) of XYZ"

now() { date +%s.%N; }
calc() { awk "BEGIN { printf \"%${2:-.3f}\", $1 }"; }  # calc EXPR [FORMAT]
# -- WORKERS independent serial pipelines ------------------------------------------------------------
pipeline() {  # pipeline K: the files K, K+WORKERS, ... one after the other
    local k=$1 f stem
    local files=("$in"/*.xyz)
    for ((j = k; j < ${#files[@]}; j += workers)); do
        f=${files[$j]}
        stem=$work/serial/$(basename "${f%.xyz}")
        OMP_NUM_THREADS=1 "$bin/prt-import" "$f" -o "$stem.i.pool" -q
        "$bin/prt-radii" "$stem.i.pool" -o "$stem.r.pool" -j 1 -q
        "$bin/prt-octree" "$stem.r.pool" -o "$stem.pool" -j 1 -q
        rm -f "$stem.i.pool" "$stem.r.pool"
    done
}
t0=$(now)
for ((k = 0; k < workers; k++)); do pipeline "$k" & done
wait
t_serial=$(calc "$(now) - $t0")
# The serial pools' section checksums (from their section tables), kept for the comparison below;
# the pools themselves go, so that the disk holds one set of pools at a time.
"$py" - "$work/serial" "$(dirname "$batch")/lib" <<'EOF'
import json, os, sys
sys.path.insert(0, sys.argv[2])
import prt_provenance as p
d = sys.argv[1]
sums = {f: {str(t): c for t, c in p.read_checksums(os.path.join(d, f)).items() if t != 1}
        for f in sorted(os.listdir(d)) if f.endswith(".pool")}
json.dump(sums, open(os.path.join(d, "checksums.json"), "w"))
EOF
rm -f "$work"/serial/*.pool

# -- prt-batch, local cluster ---------------------------------------------------------------------
t0=$(now)
"$py" "$batch" -b "$bin" -j "$workers" -t 1 -s import,radii,octree -q "$in" "$work/dask" >"$work/dask.txt" || {
    echo "bench-batch: prt-batch failed (exit $?):" >&2
    grep -v '^  ok ' "$work/dask.txt" | head -20 >&2
    exit 1
}
t_dask=$(calc "$(now) - $t0")
head -n 1 "$work/dask.txt"
t0=$(now)
"$py" "$batch" -b "$bin" -j "$workers" -t 1 -s import,radii,octree -q "$in" "$work/dask" >"$work/resume.txt"
t_resume=$(calc "$(now) - $t0")
head -n 1 "$work/resume.txt"
# The results must equal the serial pipelines' (the checksums of every section but the provenance).
"$py" - "$work/serial" "$work/dask" "$(dirname "$batch")/lib" <<'EOF'
import json, os, sys
sys.path.insert(0, sys.argv[3])
import prt_provenance as p
want = json.load(open(os.path.join(sys.argv[1], "checksums.json")))
got = {f: {str(t): c for t, c in p.read_checksums(os.path.join(sys.argv[2], f)).items() if t != 1}
       for f in want if os.path.exists(os.path.join(sys.argv[2], f))}
bad = [f for f in want if got.get(f) != want[f]]
print("# results equal the serial pipelines' for %d of %d pools" % (len(want) - len(bad), len(want)))
sys.exit(1 if bad else 0)
EOF

tasks=$((scans * 3))
printf '%-40s %10s\n' "what" "seconds"
printf '%-40s %10.2f\n' "$workers serial pipelines" "$t_serial"
printf '%-40s %10.2f\n' "prt-batch, local cluster of $workers" "$t_dask"
printf '%-40s %10.2f\n' "prt-batch again (all current: resume)" "$t_resume"
echo "throughput of prt-batch / serial pipelines: $(calc "$t_serial / $t_dask")"
echo "overhead per task: $(calc "($t_dask - $t_serial) * $workers / $tasks * 1000" .0f) ms worker-time ($tasks tasks; includes the cluster's start-up)"
echo "overhead per task without the fixed cost (the resume pass: cluster start-up, hashing, checks): $(calc "($t_dask - $t_resume - $t_serial) * $workers / $tasks * 1000" .0f) ms"
echo "(a negative overhead: the cluster's dynamic scheduling balanced files of uneven sizes better than the"
echo " round-robin split of the serial pipelines, or another load on the machine moved the times)"
echo "scans per second: serial $(calc "$scans / $t_serial" .2f), prt-batch $(calc "$scans / $t_dask" .2f)"
