#!/usr/bin/env bash
# Tests scripts/prt-batch (issue 10; on Dask since issue 21, whose own tests are
# test_prt_batch_dask.py) against the tools of a build: a folder of good and bad scans,
# outputs only for the good ones (each a valid pool), every failure named with its reason, exit
# statuses, usage errors, --help documenting every option, an existing output of a failing input
# left untouched, the optional steps, and an interrupted batch leaving no partial output.
# Usage: prt_batch_test.sh PRT_BATCH BIN_DIR   (exit 77 = skipped: the build lacks prt-import, or
# the Python prt-batch runs with lacks Dask)
set -uo pipefail
batch=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")
bin=$(cd "$2" && pwd)
if [ ! -x "$bin/prt-import" ] || [ ! -x "$bin/prt-info" ]; then
    echo "SKIP: prt-import or prt-info not built in $bin"
    exit 77
fi
python=$(head -n 1 "$batch" | sed -n 's/^#! *//p')  # prt-batch's interpreter (its first line)
if ! ${python:-python3} -c "import dask, distributed, cloudpickle" 2>/dev/null; then
    echo "SKIP: ${python:-python3} lacks Dask (python3-dask, python3-distributed), which prt-batch runs on"
    exit 77
fi

name=prt_batch_test
# shellcheck source=check_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/check_lib.sh"
valid_pool() { "$bin/prt-info" "$1" >/dev/null 2>&1; }

# sphere_xyz FILE N: N points on a unit sphere with outward normals (a scan prt-radii can handle).
sphere_xyz() {
    awk -v n="$2" 'BEGIN { pi = 3.14159265358979; g = pi * (3 - sqrt(5));
        for (i = 0; i < n; i++) { y = 1 - 2 * (i + 0.5) / n; r = sqrt(1 - y * y); t = g * i;
            printf "%.7f %.7f %.7f %.7f %.7f %.7f\n", r * cos(t), y, r * sin(t), r * cos(t), y, r * sin(t) } }' >"$1"
}

in=$work/scans
mkdir -p "$in/sub"
sphere_xyz "$in/sphere.xyz" 400
printf 'ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\nend_header\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n' >"$in/tri.ply"
printf 'ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\nproperty float z\nend_header\n1 2 3\n' >"$in/truncated.ply"
printf 'not a point cloud\n' >"$in/garbage.pcd"
printf '\x00\x01\x02binary' >"$in/binary.xyz"
: >"$in/empty.off"
cp "$in/tri.ply" "$in/sub/deep.ply"
printf 'ignored: not a scan extension\n' >"$in/notes.md"

# -- a folder with good and bad files ----------------------------------------------------------
out=$work/out
mkdir -p "$out"
printf 'previous output\n' >"$out/truncated.pool"  # an existing output of an input that now fails
"$batch" -b "$bin" -j 3 --import-args "--normals keep" "$in" "$out" >"$work/summary.txt" 2>"$work/progress.txt"
status=$?
cat "$work/summary.txt"
check "exit status 1 when a file failed" [ "$status" = 1 ]
check "summary counts" contains "$work/summary.txt" "6 files in $in: 2 ok, 4 failed, 0 skipped"
check "good PLY converted" valid_pool "$out/tri.pool"
check "good XYZ converted" valid_pool "$out/sphere.pool"
check "no output for the bad PCD" [ ! -e "$out/garbage.pool" ]
check "no output for the binary XYZ" [ ! -e "$out/binary.pool" ]
check "no output for the empty OFF" [ ! -e "$out/empty.pool" ]
check "existing output of a failing input untouched" [ "$(cat "$out/truncated.pool")" = "previous output" ]
check "truncated PLY reason" contains "$work/summary.txt" \
    "failed  $in/truncated.ply: prt-import: error: $in/truncated.ply: header declares 5 vertices but the data ends after 1"
# PCL finds no header; a build without PCL refuses every PCD file, naming what it lacks.
check "PCD reason" contains_any "$work/summary.txt" \
    "failed  $in/garbage.pcd: prt-import: error: $in/garbage.pcd: not a valid PCD file" \
    "failed  $in/garbage.pcd: prt-import: error: $in/garbage.pcd: PCD import needs PCL"
check "binary XYZ reason" contains "$work/summary.txt" "failed  $in/binary.xyz: prt-import: error: $in/binary.xyz: binary data, not XYZ text"
check "empty OFF reason" contains "$work/summary.txt" "failed  $in/empty.off: prt-import: error: $in/empty.off:"
check "ok lines" contains "$work/summary.txt" "ok      $in/tri.ply -> $out/tri.pool"
check "one failure line per bad file" [ "$(grep -c '^  failed  ' "$work/summary.txt")" = 4 ]
check "one progress line per file" [ "$(grep -c '^prt-batch: \[[0-9]/6\] ' "$work/progress.txt")" = 6 ]
check "subfolder not searched without --recursive" [ ! -e "$out/sub/deep.pool" ]
check "no work folder left" [ -z "$(find "$out" -name '.prt-batch.*')" ]
check "nothing but the outputs written" [ "$(find "$out" -type f | sort | tr '\n' ' ')" = \
    "$out/sphere.pool $out/tri.pool $out/truncated.pool " ]

# -- all good, recursive, quiet ------------------------------------------------------------------
good=$work/good
mkdir -p "$good/a/b"
cp "$in/tri.ply" "$good/one.PLY"
cp "$in/sphere.xyz" "$good/a/b/two.xyz"
"$batch" -b "$bin" -r -q "$good" "$work/good-out" >"$work/summary2.txt" 2>"$work/progress2.txt"
check "exit status 0 when every file converted" [ $? = 0 ]
check "recursive output mirrors the tree" valid_pool "$work/good-out/a/b/two.pool"
check "extensions are case-insensitive" valid_pool "$work/good-out/one.pool"
check "--quiet prints no progress" [ ! -s "$work/progress2.txt" ]
check "--skip-existing skips newer outputs" \
    bash -c "'$batch' -b '$bin' -r --skip-existing '$good' '$work/good-out' | grep -qF '0 ok, 0 failed, 2 skipped'"

# -- two inputs for one output -------------------------------------------------------------------
clash=$work/clash
mkdir -p "$clash"
cp "$in/tri.ply" "$clash/model.ply"
cp "$in/sphere.xyz" "$clash/model.xyz"
"$batch" -b "$bin" -q "$clash" "$work/clash-out" >"$work/summary3.txt" 2>&1
check "name collision fails both" [ $? = 1 ] && check "collision reason" contains "$work/summary3.txt" \
    "failed  $clash/model.ply: output $work/clash-out/model.pool would also be written from $clash/model.xyz"
check "no output on a collision" [ ! -e "$work/clash-out/model.pool" ]

# -- usage errors (exit 2) -----------------------------------------------------------------------
usage_error() { "$batch" "$@" >/dev/null 2>&1; [ $? = 2 ]; }
check "missing input folder" usage_error -b "$bin" "$work/nope" "$work/o"
check "one folder only" usage_error -b "$bin" "$in"
check "unknown option" usage_error -b "$bin" --frobnicate "$in" "$work/o"
check "unknown step" usage_error -b "$bin" -s import,mesh "$in" "$work/o"
check "steps out of order" usage_error -b "$bin" -s radii,import "$in" "$work/o"
check "bad job count" usage_error -b "$bin" -j 0 "$in" "$work/o"
mkdir -p "$work/only-import"
ln -s "$bin/prt-import" "$work/only-import/prt-import"
check "a step whose tool is missing" usage_error -b "$work/only-import" -s import,radii "$in" "$work/o"
check "missing tool named" bash -c "'$batch' -b '$work/only-import' -s import,radii '$in' '$work/o' 2>&1 | grep -qF 'prt-radii, which does not exist'"

# -- --help documents every option with its default ----------------------------------------------
"$batch" --help >"$work/help.txt"
check "--help exits 0" [ $? = 0 ]
while read -r option; do
    check "--help documents $option" grep -qE -- "$option( |,|$)" "$work/help.txt"
done < <(grep -oE 'add_argument\("(-[a-z]", ")?--[a-z-]+"' "$batch" | grep -oE -- '--[a-z-]+')
check "--help: the options were found in the script" \
    [ "$(grep -cE 'add_argument\("(-[a-z]", ")?--[a-z-]+"' "$batch")" -ge 16 ]
check "--help gives defaults" [ "$(grep -cE '\[[^]]+\]$' "$work/help.txt")" -ge 11 ]

# -- optional steps: radii and octree (when the build has them) ----------------------------------
if [ -x "$bin/prt-radii" ] && [ -x "$bin/prt-octree" ]; then
    "$batch" -b "$bin" -s import,radii,octree -j 2 "$in" "$work/steps-out" >"$work/summary4.txt" 2>/dev/null
    check "steps: exit 1 (bad files remain bad)" [ $? = 1 ]
    "$bin/prt-info" "$work/steps-out/sphere.pool" >"$work/info.txt" 2>&1
    check "steps: radii and octree sections written" bash -c "grep -q radii '$work/info.txt' && grep -q octree_nodes '$work/info.txt'"
    check "steps: a later step's failure is named with the scan" contains "$work/summary4.txt" \
        "failed  $in/tri.ply: prt-radii: error: $in/tri.ply (imported):"
    check "steps: no output when a later step failed" [ ! -e "$work/steps-out/tri.pool" ]
else
    echo "skipped: --steps import,radii,octree (prt-radii or prt-octree not built)"
fi

# -- an interrupted batch leaves no partial output and no work folder -----------------------------
big=$work/big
mkdir -p "$big"
sphere_xyz "$big/huge.xyz" 1500000
"$batch" -b "$bin" -q "$big" "$work/big-out" >/dev/null 2>&1 &
batch_pid=$!
# Terminate the batch as soon as its prt-import runs (reading 1.5M points takes far longer than
# this 10 ms poll), so the conversion is caught in flight however fast the machine is.
for _ in $(seq 3000); do
    pgrep -f "prt-import $big/huge.xyz" >/dev/null && break
    sleep 0.01
done
kill -TERM "$batch_pid"
wait "$batch_pid"
status=$?
check "terminated batch exits 143" [ "$status" = 143 ]
check "terminated batch: the conversion had not finished (input large enough)" [ ! -e "$work/big-out/huge.pool" ]
check "terminated batch: no work folder left" [ -z "$(find "$work/big-out" -name '.prt-batch.*' 2>/dev/null)" ]
sleep 0.5
check "terminated batch: its prt-import stopped too" [ -z "$(pgrep -f "$big/huge.xyz")" ]

finish_checks
