#!/usr/bin/env bash
# The README's first command: installs the Debian dependencies, builds PointRT into build/ and
# renders the sample scene to out/room.png (on the GPU when there is one, else on the CPU).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/scripts/install-deps.sh"
"$root/scripts/build.sh"
"$root/scripts/render-sample.sh"
