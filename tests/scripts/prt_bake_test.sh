#!/usr/bin/env bash
# Tests scripts/prt-bake (issue 20: the planner). Dry runs (no tools needed): the step list of each
# surface kind (splats: radii, octree, cull; iso: prt-iso only; mls: radii, prt-mls; patches:
# prt-patches only) with and without caustics and a light map (no octree for ISO, MLS or patch
# models); radii that come with the input kept; a pool made by hand (no provenance tags) treated as
# current; bad input (a model lacking what its surface needs) stopping the bake with one line naming
# the model before anything runs; missing tools; usage errors. Real runs (with the tools of the
# build; skipped with a message where they are missing): a second bake runs nothing and says so in
# one line; touching the inputs without changing them runs nothing; changing one model's source
# reruns only its chain; changing a texture reruns prt-texture and prt-iso; radii from a PLY
# "radius" property kept in the pool; the scene passes (photons, light map; photons on an ISO model
# without an octree) current on a second bake, rerun when the scene's content changes, not when it is
# touched; a failing step stops the bake with its one-line error.
# Usage: prt_bake_test.sh PRT_BAKE BIN_DIR   (exit 77 = skipped: python3 missing)
set -uo pipefail
bake=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")
bin=$(cd "$2" && pwd)
if ! command -v python3 >/dev/null; then
    echo "SKIP: python3 is not installed"
    exit 77
fi
build=$(dirname "$bin")  # prt-bake -B takes the build folder and looks in its bin/
py=$(sed -n '1s/^#! *//p' "$bake")  # prt-bake's interpreter (its content hashes: xxh3 or sha256)
[ -x "$py" ] || py=python3

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

# fake_pool FILE TYPES PROVENANCE_JSON: a pool file with the sections TYPES (comma-separated; empty
# payloads but the provenance's) as far as prt-bake reads one (header, section table, provenance):
# pools of shapes no tool makes, for the planner's decisions only.
fake_pool() {
    python3 - "$@" <<'PY'
import struct, sys
path, prov = sys.argv[1], sys.argv[3].encode()
types = sorted({int(t) for t in sys.argv[2].split(",")} | {1})
table_at = 256
data_at = (table_at + 64 * len(types) + 255) // 256 * 256
head = bytearray(64)
head[:8] = b"PRTPOOL\0"
struct.pack_into("<IxxxxQ", head, 24, len(types), table_at)
table = b"".join(struct.pack("<IIQQQIIQ16s", t, 1, data_at, len(prov) if t == 1 else 0,
                             len(prov) if t == 1 else 0, 1, 0, 1000 + t, b"") for t in types)
with open(path, "wb") as f:
    f.write(bytes(head) + bytes(table_at - 64) + table + bytes(data_at - table_at - len(table)) + prov)
PY
}
# steps FILE MODEL: the tools that run for MODEL, in order, comma-separated.
steps() { sed -n "s/^prt-bake: \[$2\] run \([a-z-]*\):.*/\1/p" "$1" | paste -sd, -; }

# -- the step list of each surface kind (dry run: nothing runs, the plan on stdout) ---------------
sphere_ply iso.ply 400
sphere_ply mls.ply 300
printf 'not read in a dry run\n' >teapot.bpt
for surface in splats iso mls; do
    cat >"$surface.json" <<EOF
{"models": [{"name": "$surface", "source": "scan.ply", "pool": "pools/$surface.pool", "surface": "$surface"}],
 "lights": [{"type": "point", "position": [0, 3, 0]}]}
EOF
done
cat >patches.json <<'EOF'
{"materials": [{"name": "tiles", "texture": "checker.pfm"}],
 "models": [{"name": "teapot", "source": "teapot.bpt", "pool": "pools/teapot.pool", "surface": "patches",
             "material": "tiles"}]}
EOF
# One scene with every surface, caustics (glass models) and a light map.
cat >effects.json <<'EOF'
{"materials": [{"name": "wall"}, {"name": "glass", "transmissivity": 0.9, "refractive_index": 1.5}],
 "models": [{"name": "room", "source": "scan.ply", "pool": "pools/room.pool", "material": "wall"},
            {"name": "ball", "source": "iso.ply", "pool": "pools/ball.pool", "material": "glass", "surface": "iso"},
            {"name": "ref", "source": "mls.ply", "pool": "pools/ref.pool", "material": "glass", "surface": "mls"},
            {"name": "teapot", "source": "teapot.bpt", "pool": "pools/teapot.pool", "material": "glass"}],
 "lights": [{"type": "point", "position": [0, 3, 0]}],
 "render": {"caustics": true, "light_map": true}}
EOF

"$bake" -B "$build" --dry-run splats.json >splats.txt 2>splats.err
check "splats: dry run exits 0" [ $? = 0 ]
cat splats.txt
check "splats: import, radii, octree, cull" [ "$(steps splats.txt splats)" = "prt-import,prt-radii,prt-octree,prt-cull" ]
check "splats: no texture" contains splats.txt "[splats] skip prt-texture: material 'default' has no texture"
check "splats: no ISO, no MLS" contains splats.txt 'skip prt-iso: surface is "splats"'
check "splats: each step gets a provenance tag" \
    contains splats.txt "prt-cull $work/pools/splats.pool -o $work/pools/splats.pool --provenance-tag TAG"
check "splats: no photons unless asked" contains splats.txt "[scene] skip prt-photons: render.caustics is false"
check "splats: no light map unless asked" contains splats.txt "[scene] skip prt-lightmap: render.light_map is false"
check "splats: dry run writes nothing" [ ! -e pools ]
"$bake" -B "$build" -n --show-tags splats.json >tags.txt 2>&1
check "--show-tags: the tag names the source's content hash" \
    contains tags.txt "\"input\":\"$("$py" -c 'import sys; sys.path.insert(0, sys.argv[1]); import prt_provenance as p; print(p.file_hash("scan.ply"))' "$(dirname "$bake")/lib")\""
"$bake" -B "$build" -n iso.json >iso.txt 2>&1
check "iso: import, prt-iso only" [ "$(steps iso.txt iso)" = "prt-import,prt-iso" ]
check "iso: no prt-radii (prt-iso computes k-NN radii)" contains iso.txt '[iso] skip prt-radii: not needed: surface "iso"'
check "iso: no octree" contains iso.txt '[iso] skip prt-octree: not needed: no splats traced (surface "iso")'
"$bake" -B "$build" -n mls.json >mls.txt 2>&1
check "mls: import, radii, prt-mls" [ "$(steps mls.txt mls)" = "prt-import,prt-radii,prt-mls" ]
check "mls: no cull" contains mls.txt '[mls] skip prt-cull: not needed'
"$bake" -B "$build" -n patches.json >patches.txt 2>&1
check "patches: prt-patches only" [ "$(steps patches.txt teapot)" = "prt-patches" ]
check "patches: the texture skipped" contains patches.txt "[teapot] skip prt-texture: a patch model has no point colors"
check "patches: no point steps listed" lacks patches.txt "prt-radii"

"$bake" -B "$build" -n effects.json >effects.txt 2>&1
check "effects: dry run exits 0" [ $? = 0 ]
check "effects: splats as without effects" [ "$(steps effects.txt room)" = "prt-import,prt-radii,prt-octree,prt-cull" ]
check "effects: iso gets no octree for photons" [ "$(steps effects.txt ball)" = "prt-import,prt-iso" ]
check "effects: mls gets no octree for photons" [ "$(steps effects.txt ref)" = "prt-import,prt-radii,prt-mls" ]
check "effects: patches get no octree" [ "$(steps effects.txt teapot)" = "prt-patches" ]
check "effects: photons" contains effects.txt "[scene] run prt-photons: model pools change in this run"
check "effects: photons command" contains effects.txt "prt-photons $work/effects.json --quiet --provenance-tag TAG"
check "effects: light map" contains effects.txt "[scene] run prt-lightmap:"
check "effects: scene passes after the models" before effects.txt "[teapot] run prt-patches" "run prt-photons"

"$bake" -B "$build" -n textured.json >textured.txt 2>&1
check "textured: texture then ISO" [ "$(steps textured.txt tex)" = "prt-import,prt-texture,prt-iso" ]
check "textured: the texture command" contains textured.txt "prt-texture $work/pools/tex.pool --image $work/checker.pfm"
"$bake" -B "$build" -n caustic.json >caustic.txt 2>&1
check "caustic: both models baked" contains caustic.txt "[room] run prt-import"
"$bake" -B "$build" -n caustic_dark.json >dark.txt 2>&1
check "caustic without a light: no photons" contains dark.txt "[scene] skip prt-photons: the scene has no light"
"$bake" -B "$build" -n caustic_off.json >off.txt 2>&1
check "caustics off: no photons" contains off.txt "skip prt-photons: render.caustics is false"
"$bake" -B "$build" -n plain.json >plain.txt 2>&1
check "no specular material: no photons" \
    contains plain.txt "[scene] skip prt-photons: no model has a reflective or transmissive material"

# Radii that come with the input (a PLY "radius" property: prt-import keeps them) are not recomputed.
awk '/^property float nz$/ { print; print "property float radius"; next }
     /^end_header$/ { print; body = 1; next }
     { print (body ? $0 " 0.05" : $0) }' scan.ply >radius.ply
sed 's/scan.ply/radius.ply/; s/"name": "splats"/"name": "radius"/; s/splats.pool/radius.pool/' splats.json >radius.json
"$bake" -B "$build" -n radius.json >radius.txt 2>&1
check "input radii: kept" contains radius.txt "[radius] skip prt-radii: radii came with the input (prt-import read them): kept"
check "input radii: octree and cull" [ "$(steps radius.txt radius)" = "prt-import,prt-octree,prt-cull" ]
"$bake" -B "$build" -n --force radius.json >radius_force.txt 2>&1
check "input radii: kept with --force too" contains radius_force.txt "[radius] skip prt-radii: radii came with the input"

# A pool made by hand (provenance entries without tags) with the sections a step makes: current.
mkdir -p hand
fake_pool hand/hand.pool 2,3,4,6,16,17,18,19 \
    '[{"tool":"prt-synth","parameters":{}},{"tool":"prt-radii","parameters":{}},{"tool":"prt-octree","parameters":{}}]'
printf '{"models": [{"name": "hand", "pool": "hand/hand.pool"}]}' >hand.json
"$bake" -B "$build" -n hand.json >hand.txt 2>&1
cat hand.txt
check "hand-made pool: octree current, said so" \
    contains hand.txt "[hand] skip prt-octree: current (made without a provenance tag, by hand"
check "hand-made pool: only prt-cull runs" [ "$(steps hand.txt hand)" = "prt-cull" ]
"$bake" -B "$build" -n --force hand.json >hand_force.txt 2>&1
check "hand-made pool: --force rebuilds" [ "$(steps hand_force.txt hand)" = "prt-radii,prt-octree,prt-cull" ]

# A bricked pool (prt-bricks: bricks, no per-point sections) keeps its bricks: no splat step runs.
fake_pool hand/bricked.pool 2,128,129,130,131,132 '[{"tool":"prt-synth","parameters":{}},{"tool":"prt-bricks","parameters":{}}]'
printf '{"models": [{"name": "big", "pool": "hand/bricked.pool"}]}' >bricked.json
"$bake" -B "$build" -n bricked.json >bricked.txt 2>&1
check "bricked pool: kept" contains bricked.txt "[big] skip prt-octree: the pool is bricked (prt-bricks): its bricks are kept"
check "bricked pool: nothing to do" contains bricked.txt "prt-bake: nothing to do: the 3 steps bricked.json needs are current"

# -- bad input: one line naming the model and what is missing, exit 1, nothing run ---------------
fake_pool hand/nonormals.pool 2,3 '[{"tool":"prt-synth","parameters":{}}]'
fake_pool hand/points.pool 2,3,4 '[{"tool":"prt-synth","parameters":{}}]'
bad() {  # bad NAME MODEL_JSON EXPECTED: a good model, then MODEL_JSON: fails with EXPECTED, runs nothing
    printf '{"models": [{"name": "ok", "source": "scan.ply", "pool": "pools/ok.pool"}, %s]}' "$2" >"bad_$1.json"
    "$bake" -B "$build" "bad_$1.json" >"bad_$1.out" 2>"bad_$1.err"
    local status=$?
    cat "bad_$1.err"
    check "bad input $1: exit 1" [ "$status" = 1 ]
    check "bad input $1: the error" contains "bad_$1.err" "$3"
    check "bad input $1: one line" [ "$(wc -l <"bad_$1.err")" = 1 ]
    check "bad input $1: nothing ran" [ ! -e pools/ok.pool ]
}
bad mls_no_normals '{"name": "bunny", "pool": "hand/nonormals.pool", "surface": "mls"}' \
    "prt-bake: error: model 'bunny': prt-mls (surface \"mls\") needs normals: pool $work/hand/nonormals.pool has no normals section"
bad patches_on_points '{"name": "pts", "pool": "hand/points.pool", "surface": "patches"}' \
    "prt-bake: error: model 'pts': surface \"patches\" needs the patch sections (prt-patches"
bad patches_from_ply '{"name": "plyp", "source": "scan.ply", "pool": "pools/plyp.pool", "surface": "patches"}' \
    "prt-bake: error: model 'plyp': surface \"patches\" needs Bezier patches (prt-patches reads a .bpt source)"
bad iso_on_teapot '{"name": "tp", "source": "teapot.bpt", "pool": "pools/tp.pool", "surface": "iso"}' \
    "prt-bake: error: model 'tp': surface \"iso\" needs points (prt-import), but the model is Bezier patches"
bad iso_on_bricks '{"name": "big", "pool": "hand/bricked.pool", "surface": "iso"}' \
    "prt-bake: error: model 'big': prt-iso needs the points: pool $work/hand/bricked.pool has no positions section (bricked without --keep-points)"
bad no_pool '{"name": "gone", "pool": "hand/gone.pool"}' \
    "prt-bake: error: model 'gone': pool $work/hand/gone.pool does not exist and the model has no source"

# -- missing tools are named before anything runs -------------------------------------------------
mkdir -p fake/bin
for t in prt-import prt-radii prt-octree prt-cull; do [ -x "$bin/$t" ] && ln -s "$bin/$t" "fake/bin/$t"; done
PATH=/usr/bin:/bin "$bake" -B "$work/fake" caustic.json >missing.out 2>missing.err
status=$?
cat missing.err
check "missing prt-photons/prt-lightmap: exit 1" [ "$status" = 1 ]
check "missing tools named: light map" contains missing.err "prt-lightmap"
check "missing tools named: photons" contains missing.err "prt-photons"
check "missing tools: where" contains missing.err "not found in $work/fake/bin or on the PATH"
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
# sections POOL: the pool's section types (comma-separated); tools POOL: its provenance's tools.
lib=$(dirname "$bake")/lib
sections() { "$py" -c 'import sys; sys.path.insert(0, sys.argv[1]); import prt_provenance as p
print(",".join(str(t[0]) for t in p.read_table(sys.argv[2])))' "$lib" "$1"; }
tools() { "$py" -c 'import sys; sys.path.insert(0, sys.argv[1]); import prt_provenance as p
print(",".join(e["tool"] for e in p.read_provenance(sys.argv[2])))' "$lib" "$1"; }
runs_nothing() { ! grep -q "\] run " "$1"; }

if have prt-import prt-radii prt-octree prt-cull; then
    "$bake" -B "$build" splats.json >run.out 2>run.err
    status=$?
    check "splats: real run exits 0" [ "$status" = 0 ]
    check "splats: pool written" [ -s pools/splats.pool ]
    check "splats: step lines on stderr" contains run.err "[splats] run prt-cull"
    check "splats: the bake's self-check finds everything current" lacks run.err "warning"
    check "splats: the pool's steps" [ "$(tools pools/splats.pool)" = "prt-import,prt-radii,prt-octree,prt-cull" ]
    "$bake" -B "$build" splats.json >again.out 2>again.err
    cat again.err
    check "splats: second bake runs nothing" runs_nothing again.err
    check "splats: second bake says so in one line" [ "$(cat again.err)" = "prt-bake: nothing to do: the 4 steps splats.json needs are current" ]
    check "splats: second bake leaves the pool alone" [ "$(tools pools/splats.pool)" = "prt-import,prt-radii,prt-octree,prt-cull" ]
    "$bake" -B "$build" -n splats.json >again.txt 2>&1
    check "splats: dry run of a current pool: skips with reasons" contains again.txt "[splats] skip prt-octree: current (same inputs and parameters)"
    "$bake" -B "$build" --quiet splats.json >quiet.out 2>quiet.err
    check "--quiet: silent" [ ! -s quiet.err ]
    "$bake" -B "$build" -n --force splats.json >force.txt 2>&1
    check "--force reruns" contains force.txt "[splats] run prt-import: --force"

    # Touching the source without changing it runs nothing: staleness is by content.
    touch -d '+1 minute' scan.ply
    "$bake" -B "$build" -n splats.json >touched.txt 2>&1
    check "touched source: nothing runs" runs_nothing touched.txt

    # Two models of two sources: changing one source's content reruns that model's chain only.
    cp scan.ply a.ply
    cp scan.ply b.ply
    cat >two.json <<'EOF'
{"models": [{"name": "a", "source": "a.ply", "pool": "pools/a.pool"},
            {"name": "b", "source": "b.ply", "pool": "pools/b.pool"}]}
EOF
    "$bake" -B "$build" --quiet two.json
    check "two models: real run exits 0" [ $? = 0 ]
    sphere_ply b.ply 500
    "$bake" -B "$build" -n two.json >changed.txt 2>&1
    cat changed.txt
    check "changed source: its chain reruns" [ "$(steps changed.txt b)" = "prt-import,prt-radii,prt-octree,prt-cull" ]
    check "changed source: said why" contains changed.txt "[b] run prt-import: its input changed (content hash differs)"
    check "changed source: the other model runs nothing" [ -z "$(steps changed.txt a)" ]

    # Radii from the input's "radius" property: kept in the pool, prt-radii never runs.
    "$bake" -B "$build" --quiet radius.json
    check "input radii: real run exits 0" [ $? = 0 ]
    check "input radii: no prt-radii step" [ "$(tools pools/radius.pool)" = "prt-import,prt-octree,prt-cull" ]
    check "input radii: the radii section" contains <(sections pools/radius.pool | tr , '\n') 6
    "$bake" -B "$build" radius.json >radius2.out 2>radius2.err
    check "input radii: second bake runs nothing" contains radius2.err "nothing to do"

    # A failing step stops the bake with the tool's error on one line.
    printf 'ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nend_header\n1\n' >broken.ply
    sed 's/scan.ply/broken.ply/; s/splats.pool/broken.pool/' splats.json >failing.json
    "$bake" -B "$build" failing.json >fail.out 2>fail.err
    status=$?
    tail -1 fail.err
    check "failing step: exit 1" [ "$status" = 1 ]
    check "failing step: named" contains fail.err "prt-bake: error: model 'splats': prt-import failed (exit 1): "
    check "failing step: the tool's reason" contains fail.err "broken.ply"
    check "failing step: later steps do not run" lacks fail.err "run prt-radii"
else
    echo "SKIP: real splat bakes (prt-import, prt-radii, prt-octree or prt-cull not built in $bin)"
fi

if have prt-import prt-texture prt-iso; then
    "$bake" -B "$build" --quiet textured.json
    check "textured: real run exits 0" [ $? = 0 ]
    check "textured: an ISO pool without splat sections" [ "$(tools pools/tex.pool)" = "prt-import,prt-texture,prt-iso" ]
    "$bake" -B "$build" -n textured.json >tex_again.txt 2>&1
    check "textured: second bake runs nothing" runs_nothing tex_again.txt
    touch -d '+1 minute' checker.pfm
    "$bake" -B "$build" -n textured.json >tex_touched.txt 2>&1
    check "touched texture: nothing runs" runs_nothing tex_touched.txt
    "$py" -c 'import struct, sys
w = h = 4
px = [0.5] * (w * h * 3)
open(sys.argv[1], "wb").write(b"PF\n%d %d\n-1\n" % (w, h) + struct.pack("<%df" % len(px), *px))' checker.pfm
    "$bake" -B "$build" -n textured.json >tex_changed.txt 2>&1
    check "changed texture: texture and ISO rerun, not the import" \
        [ "$(steps tex_changed.txt tex)" = "prt-texture,prt-iso" ]
    check "changed texture: said why" contains tex_changed.txt "[tex] run prt-texture: prt-texture ran with other inputs or parameters"
    check "changed texture: ISO after it" contains tex_changed.txt "[tex] run prt-iso: prt-texture ran after the last prt-iso"
else
    echo "SKIP: real textured bake (prt-texture or prt-iso not built in $bin)"
fi

# The scene passes: a caustic scene bakes photons and a light map once; a second bake runs nothing
# (their tags are kept beside the pools while the tools do not record them); editing the scene
# file's content reruns both passes and nothing else; touching it reruns nothing.
if have prt-import prt-radii prt-octree prt-cull prt-photons prt-lightmap; then
    "$bake" -B "$build" --quiet caustic.json 2>caustic1.err
    check "caustic: real run exits 0" [ $? = 0 ]
    check "caustic: the bake's self-check finds everything current" [ ! -s caustic1.err ]
    check "caustic: photons in the pools" contains <(tools pools/ball.pool) "prt-photons,prt-lightmap"
    "$bake" -B "$build" caustic.json >caustic2.out 2>caustic2.err
    cat caustic2.err
    check "caustic: second bake runs nothing" [ "$(cat caustic2.err)" = "prt-bake: nothing to do: the 10 steps caustic.json needs are current" ]
    touch -d '+1 minute' caustic.json
    "$bake" -B "$build" -n caustic.json >caustic_touched.txt 2>&1
    check "touched scene: nothing runs" runs_nothing caustic_touched.txt
    sed -i 's/"position": \[0, 3, 0\]/"position": [0, 2.5, 0]/' caustic.json
    "$bake" -B "$build" -n caustic.json >caustic_edit.txt 2>&1
    cat caustic_edit.txt
    check "edited scene: photons rerun" contains caustic_edit.txt "[scene] run prt-photons: pool $work/pools/room.pool: its input changed (content hash differs)"
    check "edited scene: light map reruns" contains caustic_edit.txt "[scene] run prt-lightmap:"
    check "edited scene: no model step" [ -z "$(steps caustic_edit.txt room)$(steps caustic_edit.txt ball)" ]
else
    echo "SKIP: real caustic bake (prt-cull, prt-photons or prt-lightmap not built in $bin)"
fi

# Caustics on an ISO model: photons without a splat octree (SCENE_PASS_NEEDS).
if have prt-import prt-iso prt-photons; then
    cat >iso_caustic.json <<'EOF'
{"materials": [{"name": "glass", "transmissivity": 0.9, "refractive_index": 1.5}],
 "models": [{"name": "ball", "source": "iso.ply", "pool": "pools/isoball.pool", "material": "glass", "surface": "iso"}],
 "lights": [{"type": "point", "position": [0, 3, 0]}],
 "render": {"caustics": true}}
EOF
    "$bake" -B "$build" --quiet iso_caustic.json
    check "iso caustics: real run exits 0" [ $? = 0 ]
    check "iso caustics: no octree, photons" [ "$(tools pools/isoball.pool)" = "prt-import,prt-iso,prt-photons" ]
    "$bake" -B "$build" iso_caustic.json >iso_caustic2.out 2>iso_caustic2.err
    check "iso caustics: second bake runs nothing" contains iso_caustic2.err "nothing to do"
else
    echo "SKIP: real ISO caustic bake (prt-iso or prt-photons not built in $bin)"
fi

finish_checks
