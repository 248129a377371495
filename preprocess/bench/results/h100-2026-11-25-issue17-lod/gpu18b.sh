#!/usr/bin/env bash
# Issue 18 (library) on the GPU: build with the Python module, the gpu-labelled tests (CUDA cast
# kernels, torch tensors through __cuda_array_interface__), and rays/s of 10M random rays against
# the 1M-point sphere through numpy, torch and the C++ API (scripts/bench-cast.py).
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"
exec > >(tee -a "$out/log18b.txt") 2>&1
nvidia-smi --query-gpu=name --format=csv,noheader
py=$(command -v python3); echo "python: $py $($py --version 2>&1)"
$py -c 'import sysconfig, os; p = sysconfig.get_paths()["include"]; print("Python.h:", os.path.exists(p + "/Python.h"), p)'
$py -c 'import numpy, torch; print("numpy", numpy.__version__, "torch", torch.__version__, torch.cuda.is_available())'
deps="-DCMAKE_PREFIX_PATH=$PWD/.device-deps/usr -DPRT_WITH_PCL=OFF -DPRT_WITH_OPENMESH=OFF -DPRT_WITH_OIIO=OFF -DPRT_WITH_GLFW=OFF -DCMAKE_BUILD_TYPE=Release -DPython_EXECUTABLE=$py -Dpybind11_DIR=$PWD/.device-deps/pyb213/share/cmake/pybind11"
s0=$(date +%s)
cmake -S . -B build-dev $deps > /tmp/cmake.txt 2>&1; grep -i "python\|pybind" /tmp/cmake.txt | head -5
cmake --build build-dev -j16 >/tmp/build.txt 2>&1 || { grep -E "error" /tmp/build.txt | head -30; }
echo "build: $(( $(date +%s) - s0 )) s"; ls build-dev/python 2>/dev/null | head
(cd build-dev && ctest -L gpu -j4 --timeout 300 > "$out/ctest_gpu.txt" 2>&1; tail -12 "$out/ctest_gpu.txt"; grep -E "\*\*\*Failed|Failed  |FAILED" "$out/ctest_gpu.txt" | head)
(cd build-dev && ctest -R "python|api|Api" --output-on-failure > "$out/ctest_py.txt" 2>&1; grep -E "tests passed|Failed|FAILED|passed in|failed in|Error" "$out/ctest_py.txt" | head -20)
PYTHONPATH=$PWD/build-dev/python timeout 120 $py -X faulthandler -m pytest -x -q tests/python/test_pointrt_gpu.py 2>&1 | tail -25
PYTHONPATH=$PWD/build-dev/python timeout 300 $py scripts/bench-cast.py --rays 10000000 --backend cuda --torch --bin build-dev/bin --work /tmp/wcast 2>&1 | tail -20
echo ALL_DONE
# ---- bricks against float, before (a917398) and after the LOD change, same host, same run ----
mkdir -p /tmp/old && tar xzf .device-deps/old17.tgz -C /tmp/old
(cd /tmp/old && cmake -S . -B b $deps -DPRT_WITH_PYTHON=OFF >/dev/null 2>&1 && cmake --build b -j16 --target prt-bench prt-synth prt-radii prt-octree prt-cull prt-bricks >/tmp/oldbuild.txt 2>&1 || grep error /tmp/oldbuild.txt | head)
w=/tmp/wcmp; mkdir -p $w
for v in old new; do
  bin=$PWD/build-dev/bin; [ $v = old ] && bin=/tmp/old/b/bin
  for shape in sphere room; do
    $bin/prt-synth $shape -n 1000000 -o $w/$shape.pool --quiet && $bin/prt-radii $w/$shape.pool -o $w/$shape.pool --quiet \
      && $bin/prt-octree $w/$shape.pool -o $w/$shape.pool --quiet && $bin/prt-cull $w/$shape.pool -o $w/$shape.pool --quiet \
      && $bin/prt-bricks $w/$shape.pool -o $w/$shape-$v.pool --keep-float --keep-points --quiet
  done
done
for rep in 1 2; do for shape in sphere room; do
  cam=""; [ $shape = sphere ] && cam="--eye 0,0,3 --look-at 0,0,0 --up 0,1,0 --fov 45"
  for v in old new; do
    bin=$PWD/build-dev/bin; [ $v = old ] && bin=/tmp/old/b/bin
    for mode in float bricks; do
      extra=""; [ $mode = bricks ] && extra="--bricks"
      $bin/prt-bench --backend cuda $w/$shape-$v.pool $cam $extra --frames 50 --warmup 10 --quiet --json $w/b.json >/dev/null 2>$w/be.txt || { echo "$shape $v $mode failed"; tail -2 $w/be.txt; continue; }
      python3 - "$shape $v $mode" $w/b.json <<'PY'
import json, sys
j = json.load(open(sys.argv[2]))
print(sys.argv[1].ljust(22), ' '.join('%s %.3f' % (x['name'], x['grays_per_s']) for x in j['scenarios']))
PY
    done
  done
done; done
echo CMP_DONE
