#!/usr/bin/env bash
# The public API from outside (issue 18), on a 20k-point unit sphere made by the tools:
#   examples BUILD: runs the three examples (runtime/api/examples) and checks their answers;
#   install BUILD:  installs BUILD into a temporary prefix, configures and builds the consumer
#                   project (find_package(PointRT)) against it and runs it.
set -euo pipefail
mode=$1 build=$2 here=$(cd "$(dirname "$0")" && pwd)
bin=$build/bin
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
"$bin/prt-synth" sphere -n 20000 -o "$tmp/s0.pool" -q
"$bin/prt-radii" "$tmp/s0.pool" -o "$tmp/s1.pool" -q
"$bin/prt-octree" "$tmp/s1.pool" -o "$tmp/s.pool" -q
fail() { echo "FAIL: $*" >&2; exit 1; }
case $mode in
examples)
    ex=$build/runtime/api
    # Visibility: through the sphere is blocked, past it is not; a missing file is one line, exit 1.
    [ "$("$ex/prt_example_visibility" "$tmp/s.pool" 0 0 3 0 0 -3 | head -1)" = blocked ] || fail "visibility through"
    [ "$("$ex/prt_example_visibility" "$tmp/s.pool" 0 0 3 3 0 0)" = visible ] || fail "visibility past"
    set +e
    msg=$("$ex/prt_example_visibility" "$tmp/missing.pool" 0 0 3 3 0 0 2>&1)
    rc=$?
    set -e
    [ $rc -eq 1 ] && [ "$(echo "$msg" | wc -l)" -eq 1 ] && echo "$msg" | grep -q missing.pool || fail "missing file: $rc $msg"
    # Depth map from (0, 0, 3): the nearest range is 2 (the sphere's pole), within a pixel's slant.
    out=$("$ex/prt_example_depth_map" "$tmp/s.pool" 0 0 3 "$tmp/d.pgm" 360 180)
    echo "$out"
    lo=$(echo "$out" | sed -n 's/.*range \([0-9.]*\) .*/\1/p')
    awk -v lo="$lo" 'BEGIN { exit !(lo > 1.99 && lo < 2.01) }' || fail "depth map nearest range $lo"
    [ "$(head -c 2 "$tmp/d.pgm")" = P5 ] || fail "depth map file"
    # Picking the centre of the default view: a point on the unit sphere, its normal along it.
    out=$("$ex/prt_example_picking" "$tmp/s.pool" 256 256)
    echo "$out"
    echo "$out" | awk '/^position/ { r = sqrt($2*$2 + $3*$3 + $4*$4); p[1]=$2; p[2]=$3; p[3]=$4 }
                       /^normal/ { c = ($2*p[1] + $3*p[2] + $4*p[3]) / r }
                       END { exit !(r > 0.99 && r < 1.01 && c > 0.99) }' || fail "picking"
    ;;
install)
    cmake --install "$build" --prefix "$tmp/prefix" > /dev/null
    [ -f "$tmp/prefix/include/prt/pointrt.h" ] || fail "header not installed"
    # Only the one public header is installed.
    [ "$(find "$tmp/prefix/include" -type f | wc -l)" -eq 1 ] || fail "internal headers installed"
    cmake -S "$here/consumer" -B "$tmp/consumer" -DCMAKE_PREFIX_PATH="$tmp/prefix" -DCMAKE_BUILD_TYPE=Release > /dev/null
    cmake --build "$tmp/consumer" > /dev/null
    "$tmp/consumer/consumer" "$tmp/s.pool"
    ;;
*) echo "usage: $0 examples|install BUILD" >&2; exit 2 ;;
esac
echo OK
