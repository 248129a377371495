#!/usr/bin/env bash
# Tests scripts/check-layers.py (issue 16): the tree passes; copies of it with one planted
# violation of each rule fail with a line naming the file.
# Usage: check_layers_test.sh SOURCE_DIR
set -uo pipefail
src=$(cd "$1" && pwd)
name=check_layers_test
# shellcheck source=check_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/check_lib.sh"

python3 "$src/scripts/check-layers.py" --root "$src" >"$work/tree.txt" 2>&1
check "the tree keeps the layer rule" test $? = 0

# plant VIOLATION FILE LINE: a copy of the tree with LINE appended to FILE must fail, naming FILE
plant() {
    local what=$1 file=$2 line=$3
    rm -rf "$work/copy" && mkdir -p "$work/copy"
    cp -r "$src/formats" "$src/runtime" "$src/preprocess" "$work/copy/"
    echo "$line" >>"$work/copy/$file"
    python3 "$src/scripts/check-layers.py" --root "$work/copy" >"$work/out.txt" 2>&1
    local code=$?
    check "$what: exit 1" test "$code" = 1
    check "$what: names $file" contains "$work/out.txt" "$file"
}
plant "runtime/core includes the host" runtime/core/include/prt/core/math.h '#include "prt/runtime/render_scene.h"'
plant "runtime/core includes a formats library header" runtime/core/include/prt/core/ray.h '#include "prt/formats/pool.h"'
plant "runtime includes preprocess" runtime/host/src/leaf_bounds.cpp '#include "octree_build.h"'
plant "formats includes runtime/core" formats/src/pool_reader.cpp '#include "prt/core/math.h"'
plant "a tool includes a backend's internals" preprocess/splat/cull.cpp '#include "cuda_check.h"'
finish_checks
