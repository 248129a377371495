#!/usr/bin/env bash
# Issue 20, third call: the bakes with the GPU's context created on a thread while the scene loads
# (photons::warm_up): prt-photons on the glass-sphere sample scene at three photon counts, and
# prt-lightmap on the 1M-point room, timed end to end.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"
exec > >(tee -a "$out/log20w.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
s0=$(date +%s)
cmake -S . -B build-dev "-DCMAKE_PREFIX_PATH=$PWD/.device-deps/usr" -DPRT_WITH_PCL=OFF -DPRT_WITH_OPENMESH=OFF -DPRT_WITH_OIIO=OFF -DPRT_WITH_PYTHON=OFF -DPRT_WITH_GLFW=OFF -DCMAKE_BUILD_TYPE=Release > /tmp/cmake.txt 2>&1 || tail -5 /tmp/cmake.txt
cmake --build build-dev -j16 --target prt-lightmap prt-photons prt-synth prt-radii prt-octree >/tmp/build.txt 2>&1 || { grep -E "error" /tmp/build.txt | head -30; }
echo "build: $(( $(date +%s) - s0 )) s"
BUILD_DIR=$PWD/build-dev bash scripts/make-gi-samples.sh > /tmp/gi.txt 2>&1 || tail -5 /tmp/gi.txt
for fr in 512 1024 2048; do
  echo "== prt-photons glass_sphere --face-res $fr"
  build-dev/bin/prt-photons data/scenes/glass_sphere.json --backend cuda --face-res $fr --per-pixel 8 --gather-radius 2.5 2>&1 | grep -E "photons in|phases" | tail -3
done
bin=build-dev/bin
w=/tmp/lm; rm -rf $w; mkdir -p $w
$bin/prt-synth room -n 1000000 -o $w/room.pool -q && $bin/prt-radii $w/room.pool -o $w/room.pool -q && $bin/prt-octree $w/room.pool -o $w/room.pool -q
sed -e "s|../../out/room.pool|$w/room.pool|" -e 's|"reflections": true}|"reflections": true, "light_map": true}|' data/scenes/room.json > $w/room.json
echo "== light map, 1M room, --backend cuda"
/usr/bin/time -f "wall %e s" $bin/prt-lightmap $w/room.json --backend cuda 2>&1 | grep -vE "^\s*$" | tail -3
echo "ALL_DONE $(( $(date +%s) - s0 )) s"
