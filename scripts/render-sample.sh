#!/usr/bin/env bash
# Renders the sample scene data/scenes/room.json: a synthetic closed room (prt-synth) through
# prt-radii and prt-octree into out/room.pool, then prt-play to out/room.png (GPU if present).
# Usage: scripts/render-sample.sh [POINTS]   (default 300000)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
bin=${BUILD_DIR:-$root/build}/bin
points=${1:-300000}
mkdir -p "$root/out"
pool=$root/out/room.pool
"$bin/prt-synth" room -n "$points" -o "$pool"
"$bin/prt-radii" "$pool" -o "$pool"
"$bin/prt-octree" "$pool" -o "$pool"
[ -x "$bin/prt-play" ] || { echo "render-sample: prt-play was not built" >&2; exit 1; }
scene=$root/data/scenes/room.json
image=$root/out/room.png
if ! "$bin/prt-play" --scene "$scene" --out "$image"; then
    # builds without OpenImageIO write PPM/PFM only (prt-play checks the format before rendering)
    image=$root/out/room.ppm
    "$bin/prt-play" --scene "$scene" --out "$image"
fi
echo "render-sample: wrote $image"
