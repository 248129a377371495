#!/usr/bin/env bash
# Issue 20 on the GPU machine: the light map on the GPU against the CPU (tests, label gpu), photons
# on the GPU, and the 1M-point room's light map timed on both backends (prt-lightmap, defaults:
# 64 paths of 3 vertices per sample, 4 samples per light-map leaf).
# Usage (repository root, carrying .device-deps): bash preprocess/bench/results/.../gpu20s.sh
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"
exec > >(tee -a "$out/log20s.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
nproc
s0=$(date +%s)
if [ ! -x build-dev/bin/prt-lightmap ] || [ "${REBUILD:-1}" = 1 ]; then
cmake -S . -B build-dev "-DCMAKE_PREFIX_PATH=$PWD/.device-deps/usr" -DPRT_WITH_PCL=OFF -DPRT_WITH_OPENMESH=OFF -DPRT_WITH_OIIO=OFF -DPRT_WITH_PYTHON=OFF -DPRT_WITH_GLFW=OFF -DCMAKE_BUILD_TYPE=Release > /tmp/cmake.txt 2>&1 || tail -5 /tmp/cmake.txt
cmake --build build-dev -j16 --target prt_lightmap_gpu_tests prt_photons_gpu_tests prt-lightmap prt-photons prt-synth prt-radii prt-octree prt-iso prt-mls prt-patches prt-cull >/tmp/build.txt 2>&1 || { grep -E "error" /tmp/build.txt | head -30; }
echo "build: $(( $(date +%s) - s0 )) s"
fi
(cd build-dev && ctest -L gpu -R "LightMapGpu|PhotonsGpu" --timeout 300 --output-on-failure > "$out/ctest_gpu20s.txt" 2>&1; grep -E "tests passed|\*\*\*|Failed|FAILED|Not Run|light map:" "$out/ctest_gpu20s.txt" | head -20)
grep -E "light map:" "$out/ctest_gpu20s.txt" | head
bin=build-dev/bin
w=/tmp/lm; rm -rf $w; mkdir -p $w
$bin/prt-synth room -n 1000000 -o $w/room.pool -q && $bin/prt-radii $w/room.pool -o $w/room.pool -q && $bin/prt-octree $w/room.pool -o $w/room.pool -q
sed -e "s|../../out/room.pool|$w/room.pool|" -e 's|"reflections": true}|"reflections": true, "light_map": true}|' data/scenes/room.json > $w/room.json
for b in cuda cpu; do
  echo "== light map, 1M room, --backend $b"
  /usr/bin/time -f "wall %e s, max RSS %M KB" $bin/prt-lightmap $w/room.json --backend $b --stats-json $out/lm_room_$b.json 2>&1 | grep -vE "^\s*$" | tail -4
done
# The same room traced as ISO (frame from the points after the octree is dropped is not needed: the
# pool keeps its octree; this times settled samples on the ISO surface).
$bin/prt-iso $w/room.pool -o $w/room.pool -q
sed -e 's|"surface": "splats"|"surface": "iso"|' $w/room.json > $w/room_iso.json
echo "== light map, 1M room as ISO, --backend cuda"
$bin/prt-lightmap $w/room_iso.json --backend cuda --stats-json $out/lm_room_iso_cuda.json 2>&1 | tail -3
echo "ALL_DONE $(( $(date +%s) - s0 )) s"
