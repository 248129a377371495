#!/usr/bin/env bash
# Issue 16's before/after GPU check. Usage: gpu16.sh before|after
#   before: builds the tree of .device-deps/before.tar.gz (the commit before issue 16) in /tmp/src
#   after:  builds the working tree
# Each: CUDA build (header-only deps), ctest -L gpu, prt-bench (splats/iso/mls, 1M room), and
# renders (CUDA and CPU) of a torus as splats/iso/mls, the room sample and the GI samples
# (photons on the GPU, light maps) into $OUT/images.tar; 'after' compares with
# .device-deps/images_before.tar when carried.
set -uo pipefail
mode=$1
out=${OUT:-/tmp/out}; mkdir -p "$out"
exec > >(tee -a "$out/log_$mode.txt") 2>&1
start=$(date +%s); stamp() { echo "[$(( $(date +%s) - start )) s] $*"; }
repo=$PWD
if [ "$mode" = before ]; then
  rm -rf /tmp/src && mkdir -p /tmp/src && tar -xzf .device-deps/before.tar.gz -C /tmp/src
  src=/tmp/src
else
  src=$PWD
fi
cd "$src"
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
deps="-DCMAKE_PREFIX_PATH=$repo/.device-deps/usr -DPRT_WITH_PCL=OFF -DPRT_WITH_OPENMESH=OFF -DPRT_WITH_OIIO=OFF -DPRT_WITH_GLFW=OFF -DCMAKE_BUILD_TYPE=Release"
cmake -S . -B build-dev $deps >"$out/configure_$mode.txt" 2>&1 || { tail -30 "$out/configure_$mode.txt"; exit 1; }
cmake --build build-dev -j16 >/tmp/build.txt 2>&1 || { grep -E "error" /tmp/build.txt | head -30; }
stamp built
(cd build-dev && ctest -L gpu -j4 --timeout 200 2>&1 | tail -30) | tee "$out/gpu_tests_$mode.txt"
stamp tests
bin=$src/build-dev/bin
for s in splats iso mls; do
  $bin/prt-bench --backend cuda --surface $s --frames 50 --warmup 10 --quiet --json /tmp/b.json >/dev/null 2>/tmp/be.txt || { echo "bench $s failed"; tail -3 /tmp/be.txt; continue; }
  python3 - "$s" <<'PY' | tee -a "$out/bench_$mode.txt"
import json, sys
j = json.load(open('/tmp/b.json'))
print(sys.argv[1].ljust(8), j['device'], ' '.join('%s %.3f Grays/s (%.3f ms)' % (x['name'], x['grays_per_s'], x['median_ms']) for x in j['scenarios']))
PY
done
stamp bench
img=/tmp/img_$mode; rm -rf "$img"; mkdir -p "$img" out
p=out/torus.pool
$bin/prt-synth torus -n 200000 -o $p --quiet && $bin/prt-radii $p -o $p --quiet && $bin/prt-octree $p -o $p --quiet \
  && $bin/prt-cull $p -o $p --quiet && $bin/prt-iso $p -o $p --quiet && $bin/prt-mls $p -o $p --quiet || echo "torus pipeline failed"
for s in splats iso mls; do for b in cuda cpu; do
  $bin/prt-play $p --surface $s --backend $b --width 256 --height 256 --out $img/torus_${s}_$b.pfm --quiet || echo "render torus $s $b failed"
done; done
BUILD_DIR=$src/build-dev bash scripts/render-sample.sh 200000 >/dev/null 2>&1 || echo "render-sample failed"
for b in cuda cpu; do $bin/prt-play --scene data/scenes/room.json --backend $b --width 320 --height 240 --out $img/room_$b.pfm --quiet || echo "room $b failed"; done
BUILD_DIR=$src/build-dev bash scripts/make-gi-samples.sh 0.3 >/dev/null 2>/tmp/gi.txt || { echo "gi samples failed"; tail -5 /tmp/gi.txt; }
for sc in caustic_ring glass_sphere color_room; do for b in cuda cpu; do
  $bin/prt-play --scene data/scenes/$sc.json --backend $b --width 320 --height 240 --out $img/${sc}_$b.pfm --quiet || echo "$sc $b failed"
done; done
tar -czf "$out/images_$mode.tgz" -C "$img" .
stamp images
if [ "$mode" = after ] && [ -f "$repo/.device-deps/images_before.tgz" ]; then
  mkdir -p /tmp/img_before && tar -xzf "$repo/.device-deps/images_before.tgz" -C /tmp/img_before
  python3 - /tmp/img_before "$img" <<'PY' | tee "$out/compare.txt"
import sys, os, numpy as np
def pfm(p):
    with open(p, 'rb') as f:
        kind = f.readline().strip(); w, h = map(int, f.readline().split()); s = float(f.readline())
        c = 3 if kind == b'PF' else 1
        return np.frombuffer(f.read(), dtype='<f4' if s < 0 else '>f4').reshape(h, w, c)
a, b = sys.argv[1], sys.argv[2]
for n in sorted(os.listdir(a)):
    if not os.path.exists(os.path.join(b, n)): print(n, 'missing after'); continue
    x, y = pfm(os.path.join(a, n)), pfm(os.path.join(b, n))
    same = open(os.path.join(a, n), 'rb').read() == open(os.path.join(b, n), 'rb').read()
    d = np.abs(x - y)
    print('%-28s %s  max|d| %.3g  mean|d| %.3g  pixels differing %d of %d' % (n, 'identical' if same else 'differs  ', d.max(), d.mean(), int((d.max(axis=2) > 0).sum()), d.shape[0]*d.shape[1]))
PY
fi
stamp done
