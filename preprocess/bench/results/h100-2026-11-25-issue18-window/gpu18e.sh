#!/usr/bin/env bash
# Issue 18: prt-play's window on the GPU under Xvfb with the NVIDIA GLX vendor library.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"
exec > >(tee -a "$out/log18e.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
s0=$(date +%s)
mkdir -p /tmp/xroot && tar -C /tmp/xroot -xJf .gl/gl-root.tar.xz
echo "unpack: $(( $(date +%s) - s0 )) s"
ls /usr/local/nvidia/lib64 2>/dev/null | grep -i glx | head; ldconfig -p | grep -i "GLX_nvidia\|libGL.so\|libglfw" | head
R=/tmp/xroot
export LD_LIBRARY_PATH=$R/usr/lib/x86_64-linux-gnu${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
deps="-DCMAKE_PREFIX_PATH=$PWD/.device-deps/usr;$R/usr -DPRT_WITH_PCL=OFF -DPRT_WITH_OPENMESH=OFF -DPRT_WITH_OIIO=OFF -DPRT_WITH_GLFW=ON -DPRT_WITH_PYTHON=OFF -DCMAKE_BUILD_TYPE=Release"
cmake -S . -B build-dev $deps > /tmp/cmake.txt 2>&1 || tail -20 /tmp/cmake.txt
grep -i "glfw\|opengl\|interop" /tmp/cmake.txt | head
cmake --build build-dev -j16 --target prt-play prt-synth prt-radii prt-octree prt_window_gpu_tests prt_runtime_tests >/tmp/build.txt 2>&1 || { grep -E "error" /tmp/build.txt | head -30; }
echo "build: $(( $(date +%s) - s0 )) s"
W="scripts/gpu-window.sh --root $R"
$W -- $R/usr/bin/glxinfo -B 2>&1 | head -20
(cd build-dev && ../$W -- ctest -R "Window" --output-on-failure > "$out/ctest_window.txt" 2>&1; grep -E "tests passed|\*\*\*|Failed|FAILED|interop" "$out/ctest_window.txt" | head -20)
b=build-dev/bin; mkdir -p out
$b/prt-synth room -n 1000000 -o out/room.pool --quiet && $b/prt-radii out/room.pool -o out/room.pool --quiet && $b/prt-octree out/room.pool -o out/room.pool --quiet
$b/prt-synth room --scan --scanners 4 --sample-step 0.147 --line-step 0.147 --range-noise 0.0003 --scan-normals -o out/scan.pool 2>&1 | grep returns
$b/prt-radii out/scan.pool -o out/scan.pool --quiet && $b/prt-octree out/scan.pool -o out/scan.pool --quiet
echo "models: $(( $(date +%s) - s0 )) s"
for m in room scan; do
  for mode in "" "--no-interop"; do
    echo "== $m $mode"
    $W -- $b/prt-play --scene data/scenes/room.json out/$m.pool --backend cuda --width 1920 --height 1080 --frames 200 $mode --screenshot "/tmp/win_${m}${mode:+_tex}.ppm" 2>&1 | grep -E "window 19|interop|wrote|error" 
  done
  $b/prt-play --scene data/scenes/room.json out/$m.pool --backend cuda --width 1920 --height 1080 --frames 20 --out /tmp/h.ppm 2>&1 | tail -2
done
cp /tmp/win_room.ppm /tmp/win_scan.ppm "$out/" 2>/dev/null
echo ALL_DONE
