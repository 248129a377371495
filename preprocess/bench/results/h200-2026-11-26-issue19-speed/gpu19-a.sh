#!/bin/bash
# Issue 19, round A: the SASS of the splat megakernel (render_kernel<1,4,1>) now and before the
# regression (81d1185), compiled on the dev VM and carried in .device-deps/sass; then the working
# tree built with the --min-blocks tuning kernels and prt-bench's room at 2-5 blocks per SM.
set -uo pipefail
OUT=${OUT:-/tmp/out}
mkdir -p "$OUT"
exec > >(tee "$OUT/a.txt") 2>&1
nvidia-smi --query-gpu=name,clocks.sm,clocks.max.sm,power.limit,temperature.gpu --format=csv
ls /usr/local/cuda/bin | tr '\n' ' '; echo
for t in cur old81; do
    /usr/local/cuda/bin/cuobjdump -sass -fun '_ZN3prt4cuda48_GLOBAL__N__876b7982_15_cuda_backend_cu_89c7d3f913render_kernelILb1ELi4ELj1EEEvNS_4core9SceneViewENS3_13PinholeCameraEjjjjPfPjPy' .device-deps/sass/$t.cubin > $OUT/$t.sass 2>&1 || true
    [ -s $OUT/$t.sass ] || /usr/local/cuda/bin/cuobjdump -sass .device-deps/sass/$t.cubin > $OUT/$t-all.sass 2>&1
    wc -l $OUT/$t*.sass
done
flags="-DCMAKE_PREFIX_PATH=$PWD/.device-deps/usr -DPRT_WITH_PCL=OFF -DPRT_WITH_OPENMESH=OFF -DPRT_WITH_OIIO=OFF -DPRT_WITH_PYTHON=OFF -DPRT_WITH_GLFW=OFF -DCMAKE_BUILD_TYPE=Release"
t0=$SECONDS
cmake -S . -B /tmp/bt $flags -DPRT_CUDA_TUNING_KERNELS=ON >/tmp/bt.cmake.txt 2>&1 &&
    cmake --build /tmp/bt -j16 --target prt-bench >/tmp/bt.build.txt 2>&1 || tail -30 /tmp/bt.build.txt
echo "build: $((SECONDS - t0)) s"
for mb in 4 3 2 5 4; do
    /tmp/bt/bin/prt-bench --scenarios primary,shadow,reflect4 --min-blocks $mb -q --json $OUT/mb$mb.json >/dev/null 2>&1
    python3 -c "
import json; d = json.load(open('$OUT/mb$mb.json'))
print('min-blocks $mb', d.get('device'), [(s.get('name'), round(s['grays_per_s'], 3), round(s.get('leaves_per_ray', 0), 2)) for s in d['scenarios']])"
done
