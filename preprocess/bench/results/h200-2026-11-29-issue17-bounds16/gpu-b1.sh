#!/usr/bin/env bash
# Issue 17 on the GPU host (one H200): brick leaf bounds in 16 bytes (core::BrickLeafBounds) instead
# of 32 (core::LeafBounds). First the GPU suites (the gtest binaries of `ctest -L gpu`, built on the
# dev VM), then bricks against the float octree on the culled 1M room and sphere, the tree before
# (HEAD_BENCH, c7a341b's prt-bench) against this one, alternating, two rounds.
# Usage (repository root): BIN=build-cuda/bin HEAD_BENCH=<old prt-bench> bash .../gpu-b1.sh
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/b1.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; nproc
bin=$(cd "$BIN" && pwd); t0=$SECONDS
old=$(cd "$(dirname "$HEAD_BENCH")" && pwd)/$(basename "$HEAD_BENCH"); w=/tmp/w1m; mkdir -p $w
for t in runtime/prt_runtime_gpu_tests runtime/prt_brick_stream_gpu_tests stability/prt_stability_gpu_tests \
         preprocess/iso/prt_iso_gpu_tests preprocess/splat/prt_cull_gpu_tests preprocess/splat/prt_radii_gpu_tests \
         preprocess/patches/prt_patches_gpu_tests preprocess/mls/prt_mls_gpu_tests; do
  echo "== $t"; build-cuda/tests/$t --gtest_filter='-*Window*:*Photon*:*LightMap*:*MlsGpu*' 2>&1 | grep -E "^\[  (PASSED|FAILED|SKIPPED) |^\[==========\] [0-9]+ tests? from .* ran|Failure" | head -12
done
echo "tests done $((SECONDS - t0)) s"
sm() { python3 - "$1" "$2" <<'PY'
import json, sys
j = json.load(open(sys.argv[2]))
print(sys.argv[1].ljust(24), ' '.join('%s %.3f' % (x['name'], x['grays_per_s']) for x in j['scenarios']))
PY
}
for shape in room sphere; do
  $bin/prt-synth $shape -n 1000000 -o $w/$shape.pool --quiet && $bin/prt-radii $w/$shape.pool -o $w/$shape.pool --quiet \
    && $bin/prt-octree $w/$shape.pool -o $w/$shape.pool --quiet && $bin/prt-cull $w/$shape.pool -o $w/$shape.pool --quiet \
    && $bin/prt-bricks $w/$shape.pool -o $w/$shape-b.pool --keep-float --quiet || echo "pool $shape failed"
done
for round in 1 2; do
  for shape in room sphere; do
    c=""; sc="primary,shadow,reflect4,full4"; [ $shape = sphere ] && { c="--eye 0,0,3 --look-at 0,0,0 --up 0,1,0 --fov 45"; sc="primary,shadow"; }
    for mode in float bricks; do
      extra="--bricks"; [ $mode = float ] && extra=""
      for who in old new; do
        b=$bin/prt-bench; [ $who = old ] && b=$old
        $b --backend cuda $w/$shape-b.pool $c $extra --scenarios $sc --frames 30 --warmup 5 --quiet --json $w/b.json >/dev/null 2>$w/be.txt || { echo "$shape $mode $who failed"; tail -2 $w/be.txt; continue; }
        sm "r$round $shape $mode $who" $w/b.json
      done
    done
  done
done
echo "ALL_DONE $((SECONDS - t0)) s"
