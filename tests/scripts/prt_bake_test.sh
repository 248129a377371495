#!/usr/bin/env bash
# Tests scripts/prt-bake: which steps run and which are skipped (with their reasons) for a plain
# scene (no photons, texture or light map), a textured ISO scene (prt-texture, then prt-iso), and
# caustic / light-map scenes (prt-photons, prt-lightmap asked for only when the scene needs them);
# staleness (a second bake runs nothing, a newer source or texture reruns what depends on it); a
# failing step stopping the bake with its one-line error; missing tools named before anything runs;
# usage errors. The decisions are checked with --dry-run everywhere; the real runs need the tools of
# the build (prt-import, prt-radii, prt-octree, prt-texture, prt-iso) and are skipped with a message
# where they are missing.
# Usage: prt_bake_test.sh PRT_BAKE BIN_DIR   (exit 77 = skipped: python3 missing)
set -uo pipefail
bake=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")
bin=$(cd "$2" && pwd)
if ! command -v python3 >/dev/null; then
    echo "SKIP: python3 is not installed"
    exit 77
fi
build=$(dirname "$bin")  # prt-bake -B takes the build folder and looks in its bin/

name=prt_bake_test
# shellcheck source=check_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/check_lib.sh"
lacks() { ! grep -qF -- "$2" "$1"; }
# before FILE A B: the first line holding A comes before the first line holding B.
before() {
    local a b
    a=$(grep -nF -- "$2" "$1" | head -1 | cut -d: -f1)
    b=$(grep -nF -- "$3" "$1" | head -1 | cut -d: -f1)
    [ -n "$a" ] && [ -n "$b" ] && [ "$a" -lt "$b" ]
}
have() {  # have TOOL...: all built
    local t
    for t in "$@"; do [ -x "$bin/$t" ] || return 1; done
}

# A sphere scan as PLY with normals (N points), and a 4 x 4 PFM texture (linear floats).
sphere_ply() {
    {
        printf 'ply\nformat ascii 1.0\nelement vertex %d\nproperty float x\nproperty float y\nproperty float z\n' "$2"
        printf 'property float nx\nproperty float ny\nproperty float nz\nend_header\n'
        awk -v n="$2" 'BEGIN { pi = 3.14159265358979; g = pi * (3 - sqrt(5));
            for (i = 0; i < n; i++) { y = 1 - 2 * (i + 0.5) / n; r = sqrt(1 - y * y); t = g * i;
                printf "%.7f %.7f %.7f %.7f %.7f %.7f\n", r * cos(t), y, r * sin(t), r * cos(t), y, r * sin(t) } }'
    } >"$1"
}
texture_pfm() {
    python3 -c '
import struct, sys
w = h = 4
px = [0.9 if (x + y) % 2 else 0.1 for y in range(h) for x in range(w) for c in range(3)]
with open(sys.argv[1], "wb") as f:
    f.write(b"PF\n%d %d\n-1\n" % (w, h))
    f.write(struct.pack("<%df" % len(px), *px))
' "$1"
}

cd "$work" || exit 1
sphere_ply scan.ply 600
texture_pfm checker.pfm

cat >plain.json <<'EOF'
{"models": [{"name": "scan", "source": "scan.ply", "pool": "pools/scan.pool"}],
 "lights": [{"type": "point"}],
 "render": {"caustics": true}}
EOF
cat >textured.json <<'EOF'
{"materials": [{"name": "checker", "diffuse": [1, 1, 1], "texture": "checker.pfm"}],
 "models": [{"name": "tex", "source": "scan.ply", "pool": "pools/tex.pool", "material": "checker",
             "surface": "iso"}]}
EOF
cat >caustic.json <<'EOF'
{"materials": [{"name": "wall"}, {"name": "glass", "transmissivity": 0.9, "diffuse_reflectance": 0.1,
                "refractive_index": 1.5}],
 "models": [{"name": "room", "source": "scan.ply", "pool": "pools/room.pool", "material": "wall"},
            {"name": "ball", "source": "scan.ply", "pool": "pools/ball.pool", "material": "glass"}],
 "lights": [{"type": "point", "position": [0, 3, 0]}],
 "render": {"caustics": true, "light_map": true}}
EOF
sed 's/"lights": \[{"type": "point", "position": \[0, 3, 0\]}\],//' caustic.json >caustic_dark.json
sed 's/"caustics": true, "light_map": true/"caustics": false, "light_map": false/' caustic.json >caustic_off.json

# -- decisions (dry run: nothing runs, the plan on stdout) ---------------------------------------
"$bake" -B "$build" --dry-run plain.json >plain.txt 2>plain.err
check "plain: dry run exits 0" [ $? = 0 ]
cat plain.txt
check "plain: imports the missing pool" contains plain.txt "[scan] run prt-import: the pool"
check "plain: radii then octree" before plain.txt "run prt-radii" "run prt-octree"
check "plain: no texture" contains plain.txt "[scan] skip prt-texture: material 'default' has no texture"
check "plain: no ISO, no MLS" contains plain.txt 'skip prt-iso: surface is "splats"'
check "plain: no photons without a specular material" \
    contains plain.txt "[scene] skip prt-photons: no model has a reflective or transmissive material"
check "plain: no light map unless asked" contains plain.txt "[scene] skip prt-lightmap: render.light_map is false"
check "plain: dry run writes nothing" [ ! -e pools ]

"$bake" -B "$build" -n textured.json >textured.txt 2>&1
check "textured: dry run exits 0" [ $? = 0 ]
check "textured: texture runs" contains textured.txt "[tex] run prt-texture:"
check "textured: the texture command" contains textured.txt "prt-texture $work/pools/tex.pool --image $work/checker.pfm"
check "textured: ISO asked for" contains textured.txt "[tex] run prt-iso:"
check "textured: texture before ISO (ISO leaves store colors)" before textured.txt "run prt-texture" "run prt-iso"
check "textured: no photons" contains textured.txt "skip prt-photons: render.caustics is false"

"$bake" -B "$build" -n caustic.json >caustic.txt 2>&1
check "caustic: dry run exits 0" [ $? = 0 ]
check "caustic: photons asked" contains caustic.txt "[scene] run prt-photons:"
check "caustic: photons command" contains caustic.txt "prt-photons $work/caustic.json --quiet"
check "caustic: light map asked" contains caustic.txt "[scene] run prt-lightmap:"
check "caustic: scene passes after the models" before caustic.txt "[ball] run prt-octree" "run prt-photons"
check "caustic: both models baked" contains caustic.txt "[room] run prt-import"
"$bake" -B "$build" -n caustic_dark.json >dark.txt 2>&1
check "caustic without a light: no photons" contains dark.txt "[scene] skip prt-photons: the scene has no light"
"$bake" -B "$build" -n caustic_off.json >off.txt 2>&1
check "caustics off: no photons" contains off.txt "skip prt-photons: render.caustics is false"
check "light map off" contains off.txt "skip prt-lightmap: render.light_map is false"

# -- missing tools are named before anything runs -------------------------------------------------
mkdir -p fake/bin
for t in prt-import prt-radii prt-octree; do [ -x "$bin/$t" ] && ln -s "$bin/$t" "fake/bin/$t"; done
PATH=/usr/bin:/bin "$bake" -B "$work/fake" caustic.json >missing.out 2>missing.err
status=$?
cat missing.err
check "missing prt-photons/prt-lightmap: exit 1" [ "$status" = 1 ]
check "missing tools named" contains missing.err "prt-lightmap, prt-photons not found in $work/fake/bin"
check "missing tools: one line" [ "$(wc -l <missing.err)" = 1 ]
check "missing tools: nothing ran" [ ! -e pools/room.pool ]

# -- usage errors ----------------------------------------------------------------------------------
"$bake" no_such_scene.json >/dev/null 2>usage.err
check "missing scene: exit 2" [ $? = 2 ]
check "missing scene named" contains usage.err "no_such_scene.json"
printf '{"models": [' >broken.json
"$bake" broken.json >/dev/null 2>usage.err
check "invalid JSON: exit 2" [ $? = 2 ]
check "invalid JSON: file named" contains usage.err "broken.json: invalid JSON"
printf '{"models": [{"source": "scan.ply", "material": "nope"}]}' >badmat.json
"$bake" badmat.json >/dev/null 2>usage.err
check "unknown material: exit 2" [ $? = 2 ]
check "unknown material: pointer" contains usage.err '/models/0/material: no material named "nope"'
"$bake" --jobs 0 plain.json >/dev/null 2>&1
check "--jobs 0: exit 2" [ $? = 2 ]
"$bake" --help >help.txt
for opt in --jobs --force --quiet --dry-run --build-dir "default 1"; do
    check "--help documents $opt" contains help.txt "$opt"
done

# -- real runs --------------------------------------------------------------------------------------
if have prt-import prt-radii prt-octree; then
    "$bake" -B "$build" plain.json >run.out 2>run.err
    status=$?
    check "plain: real run exits 0" [ "$status" = 0 ]
    check "plain: pool written" [ -s pools/scan.pool ]
    check "plain: step lines on stderr" contains run.err "[scan] run prt-octree"
    "$bake" -B "$build" -n plain.json >again.txt 2>&1
    check "plain: second bake runs nothing" lacks again.txt " run "
    check "plain: up to date" contains again.txt "[scan] skip prt-octree: up to date"
    check "plain: import skipped" contains again.txt "[scan] skip prt-import: the pool is newer than the source"
    "$bake" -B "$build" --quiet plain.json >quiet.out 2>quiet.err
    check "--quiet: silent" [ ! -s quiet.err ]
    "$bake" -B "$build" -n --force plain.json >force.txt 2>&1
    check "--force reruns" contains force.txt "[scan] run prt-import: --force"
    touch -d '+2 seconds' scan.ply
    "$bake" -B "$build" -n plain.json >newer.txt 2>&1
    check "newer source: import again" contains newer.txt "[scan] run prt-import: the source is newer than the pool"
    touch -d '-1 minute' scan.ply

    # A failing step stops the bake with the tool's error on one line.
    printf 'ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nend_header\n1\n' >broken.ply
    sed 's/scan.ply/broken.ply/; s/scan.pool/broken.pool/' plain.json >failing.json
    "$bake" -B "$build" failing.json >fail.out 2>fail.err
    status=$?
    tail -1 fail.err
    check "failing step: exit 1" [ "$status" = 1 ]
    check "failing step: named" contains fail.err "prt-bake: error: model 'scan': prt-import failed (exit 1): "
    check "failing step: the tool's reason" contains fail.err "broken.ply"
    check "failing step: later steps do not run" lacks fail.err "run prt-radii"
else
    echo "SKIP: real plain bake (prt-import, prt-radii or prt-octree not built in $bin)"
fi

if have prt-import prt-radii prt-octree prt-texture prt-iso; then
    "$bake" -B "$build" --quiet textured.json
    check "textured: real run exits 0" [ $? = 0 ]
    "$bake" -B "$build" -n textured.json >tex_again.txt 2>&1
    check "textured: second bake runs nothing" lacks tex_again.txt " run "
    check "textured: texture up to date" contains tex_again.txt "[tex] skip prt-texture: up to date"
    touch -d '+2 seconds' checker.pfm
    "$bake" -B "$build" -n textured.json >tex_newer.txt 2>&1
    check "newer texture: rebaked" contains tex_newer.txt "[tex] run prt-texture: the texture image is newer than the pool"
    check "newer texture: ISO rebuilt after it" contains tex_newer.txt "[tex] run prt-iso: prt-texture ran after the last prt-iso"
    check "newer texture: points kept" contains tex_newer.txt "[tex] skip prt-octree: up to date"
else
    echo "SKIP: real textured bake (prt-texture or prt-iso not built in $bin)"
fi

finish_checks
