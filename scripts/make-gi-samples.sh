#!/usr/bin/env bash
# Builds the pools of the global-illumination sample scenes (thesis 5.3-5.4) into out/gi/ with
# prt-synth, prt-radii and prt-octree, then bakes them with prt-photons and prt-lightmap:
#   data/scenes/caustic_ring.json   a mirror ring casting a cardioid caustic on a floor (5.4)
#   data/scenes/glass_sphere.json   a glass sphere focusing light on a wall (5.4) + light map (5.3)
#   data/scenes/color_room.json     a closed room with red and green walls: color bleeding (5.3)
# Usage: scripts/make-gi-samples.sh [SCALE]   SCALE multiplies every point count (default 1)
# Environment: BUILD_DIR (default build/), PHOTON_ARGS / LIGHTMAP_ARGS (extra tool options).
# Then: prt-play --scene data/scenes/NAME.json --backend cpu --out out/NAME.png
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
bin=${BUILD_DIR:-$root/build}/bin
scale=${1:-1}
out=$root/out/gi
mkdir -p "$out"
for tool in prt-synth prt-radii prt-octree prt-photons prt-lightmap; do
    [ -x "$bin/$tool" ] || { echo "make-gi-samples: $bin/$tool was not built" >&2; exit 1; }
done
n() { python3 -c "print(max(1000, int($1 * $scale)))"; }
pool() {  # pool NAME SYNTH-ARGS...
    local name=$1; shift
    "$bin/prt-synth" "$@" -o "$out/$name.pool" --quiet
    "$bin/prt-radii" "$out/$name.pool" -o "$out/$name.pool" --quiet
    "$bin/prt-octree" "$out/$name.pool" -o "$out/$name.pool" --quiet
    echo "make-gi-samples: $out/$name.pool"
}
pool floor plane --size 4 -n "$(n 250000)"
pool ring_floor plane --size 3 -n "$(n 250000)"
pool wall plane --size 3 -n "$(n 150000)"
pool sphere sphere --radius 0.5 -n "$(n 60000)"
pool ring ring --radius 0.8 --thickness 0.03 --height 0.3 -n "$(n 120000)"
pool color_room room --size 2 -n "$(n 300000)"
"$bin/prt-photons" "$root/data/scenes/caustic_ring.json" ${PHOTON_ARGS:-}
# The glass ball's faint reflection caustic is sparse: more photons and a wider gather footprint.
"$bin/prt-photons" "$root/data/scenes/glass_sphere.json" --per-pixel 8 --gather-radius 2.5 ${PHOTON_ARGS:-}
"$bin/prt-lightmap" "$root/data/scenes/glass_sphere.json" ${LIGHTMAP_ARGS:-}
"$bin/prt-lightmap" "$root/data/scenes/color_room.json" ${LIGHTMAP_ARGS:-}
echo "make-gi-samples: done; render with $bin/prt-play --scene data/scenes/NAME.json --backend cpu --out out/NAME.png"
