#!/usr/bin/env bash
# One batched GPU session (the device tool allows few calls): build, GPU tests, prt-bench runs over
# the settings that matter for secondary rays, an Nsight Compute profile of reflect4, prt-play, and
# prt-cull's culled pool. Usage, from the repository root on the GPU machine:
#   preprocess/bench/gpu_session.sh OUTDIR [step...]
# Steps: matrix (the first session's settings sweep), tests, final (defaults, before/after, the
# kernel variants and a second build with PRT_BATCHED_WALK=ON), ncu, play, cull. build-dev has the
# --min-blocks tuning kernels (PRT_CUDA_TUNING_KERNELS=ON) for the matrix and final steps. Results:
# OUTDIR/log.txt, OUTDIR/summary.txt (one line per prt-bench run, written as it goes),
# OUTDIR/bench.jsonl (each run's JSON on one line), OUTDIR/ncu.txt.
set -uo pipefail
out=${1:?usage: gpu_session.sh OUTDIR [steps...]}
shift
steps=${*:-"final tests ncu play cull"}
mkdir -p "$out"
exec > >(tee -a "$out/log.txt") 2>&1
start=$(date +%s)
stamp() { echo "[$(( $(date +%s) - start )) s] $*"; }
deps="-DCMAKE_PREFIX_PATH=$PWD/.device-deps/usr -DPRT_WITH_PCL=OFF -DPRT_WITH_OPENMESH=OFF -DPRT_WITH_OIIO=OFF
      -DPRT_WITH_GLFW=OFF -DPRT_WITH_FLANN=OFF -DCMAKE_BUILD_TYPE=Release"
bench=build-dev/bin/prt-bench

nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm,temperature.gpu --format=csv
stamp "configure + build (build-dev; build-batched: PRT_BATCHED_WALK=ON when the final step runs)"
cmake -S . -B build-dev $deps -DPRT_CUDA_TUNING_KERNELS=ON >"$out/configure.txt" 2>&1 \
    || { tail -40 "$out/configure.txt"; exit 1; }
case " $steps " in *" final "*)
    cmake -S . -B build-batched $deps -DPRT_BATCHED_WALK=ON \
        >>"$out/configure.txt" 2>&1 || { tail -40 "$out/configure.txt"; exit 1; }
    cmake --build build-batched -j6 --target prt-bench >"$out/build_batched.txt" 2>&1 &
    alt=$!
    ;;
esac
cmake --build build-dev -j10 --target prt-bench prt-play prt_runtime_gpu_tests >"$out/build.txt" 2>&1 \
    || { grep -E "error|Error" "$out/build.txt" | head -40; exit 1; }
[ -n "${alt:-}" ] && { wait $alt || { echo "build-batched failed"; grep -E "error" "$out/build_batched.txt" | head; }; }
stamp built

summarize() {  # one summary line per bench JSON
    python3 - "$1" "$2" <<'PY'
import json, sys
name, path = sys.argv[1], sys.argv[2]
j = json.load(open(path))
r = {s['name']: s for s in j.get('scenarios', [])}
sec = (j.get('per_ray_kind') or {}).get('secondary') or {}
cell = lambda n: f"{r[n]['median_ms']:.3f} ({r[n]['grays_per_s']:.3f})" if n in r else '-'
print(f"{name:16} {j['model']['splats']:>9} {cell('primary'):>17} {cell('shadow'):>17} {cell('reflect4'):>17} "
      f"{sec.get('leaves_per_ray', 0):5.1f}/{sec.get('culled_leaves_per_ray', 0):4.1f}/{sec.get('splat_tests_per_ray', 0):6.1f}  {j['device']}")
PY
}

run_bench() {  # name, binary, args...
    local name=$1 bin=$2
    shift 2
    stamp "bench $name: $*"
    if $bin --quiet --frames ${FRAMES:-100} --warmup ${WARMUP:-10} --json /tmp/bench.json "$@" | grep -v "^prt-bench:"; then
        summarize "$name" /tmp/bench.json >>"$out/summary.txt"
        python3 -c "import json; j=json.load(open('/tmp/bench.json')); j['run']='$name'; print(json.dumps(j))" \
            >>"$out/bench.jsonl"
    else
        echo "bench $name failed"
    fi
}

echo "run                 splats  primary ms (Grays/s) shadow ms (Grays/s) reflect4 ms (Grays/s) secondary leaves/culled/tests" >"$out/summary.txt"

for step in $steps; do
    case $step in
    matrix)
        FRAMES=30 WARMUP=5
        for c in 0 1 2; do run_bench cull$c $bench --backend cuda --leaf-culling $c; done
        run_bench cull2_leaf16 $bench --backend cuda --max-leaf 16
        run_bench cull2_leaf64 $bench --backend cuda --max-leaf 64
        run_bench cull0_leaf64 $bench --backend cuda --leaf-culling 0 --max-leaf 64
        for b in 4 5 2; do run_bench cull2_blocks$b $bench --backend cuda --min-blocks $b; done
        run_bench cull2_wave $bench --backend cuda --kernel wavefront
        run_bench cull2_again $bench --backend cuda
        run_bench cull0_again $bench --backend cuda --leaf-culling 0
        unset FRAMES WARMUP
        ;;
    final)
        run_bench default $bench --backend cuda
        run_bench before_cull0 $bench --backend cuda --leaf-culling 0
        [ -x build-batched/bin/prt-bench ] && run_bench batched build-batched/bin/prt-bench --backend cuda
        [ -x build-batched/bin/prt-bench ] && run_bench batched_cull0 build-batched/bin/prt-bench --backend cuda \
            --leaf-culling 0
        run_bench default_again $bench --backend cuda
        run_bench linear $bench --backend cuda --mapping linear
        run_bench wavefront $bench --backend cuda --kernel wavefront
        run_bench leaf64 $bench --backend cuda --max-leaf 64
        run_bench blocks4 $bench --backend cuda --min-blocks 4
        run_bench blocks5 $bench --backend cuda --min-blocks 5
        run_bench hybrid $bench --backend hybrid
        ;;
    tests)
        stamp "gpu tests"
        build-dev/tests/runtime/prt_runtime_gpu_tests 2>&1 | tail -14
        ;;
    ncu)
        ncu=$(command -v ncu || ls /opt/nvidia/nsight-compute/*/ncu 2>/dev/null | head -1)
        [ -z "$ncu" ] && { echo "ncu not found"; continue; }
        stamp "ncu reflect4 (defaults)"
        timeout 100 $ncu --section SpeedOfLight --section Occupancy --section MemoryWorkloadAnalysis \
            --section WarpStateStats --section SchedulerStats -k regex:render_kernel --launch-skip 3 --launch-count 1 \
            $bench --backend cuda --quiet --scenarios reflect4 --frames 1 --warmup 3 >>"$out/ncu.txt" 2>&1 \
            || echo "ncu run failed"
        grep -E "Duration|Achieved Occupancy|Compute \(SM\) Throughput|L1/TEX Hit|L2 Hit|Spilling Requests  |Issued Warp|Active Threads|Not Predicated" "$out/ncu.txt"
        ;;
    play)
        stamp "prt-play: the room pool, 1024x1024, 50 frames (frame download included)"
        $bench --backend cuda --quiet --frames 1 --warmup 0 --scenarios primary --save-pool /tmp/room.pool >/dev/null
        build-dev/bin/prt-play /tmp/room.pool --scene preprocess/bench/bench_room.json --backend cuda \
            --frames 50 --out /tmp/f.ppm 2>&1 | grep -E "load|frame"
        ;;
    cull)
        stamp "prt-cull (thesis 3.4) on the room pool, then the same benchmark on the culled pool"
        [ -f /tmp/room.pool ] || $bench --backend cuda --quiet --frames 1 --warmup 0 --scenarios primary \
            --save-pool /tmp/room.pool >/dev/null
        cmake --build build-dev -j16 --target prt-cull >"$out/build_cull.txt" 2>&1 \
            || { echo "prt-cull does not build"; grep -E "error" "$out/build_cull.txt" | head; continue; }
        timeout 120 build-dev/bin/prt-cull /tmp/room.pool -o /tmp/culled.pool --backend cuda 2>&1 | tail -4 \
            || echo "prt-cull failed or timed out"
        if [ -f /tmp/culled.pool ]; then
            run_bench room_scene $bench /tmp/room.pool --scene preprocess/bench/bench_room.json --backend cuda
            run_bench culled $bench /tmp/culled.pool --scene preprocess/bench/bench_room.json --backend cuda
            run_bench culled_cull0 $bench /tmp/culled.pool --scene preprocess/bench/bench_room.json --backend cuda \
                --leaf-culling 0
        fi
        ;;
    esac
done
stamp "summary"
cat "$out/summary.txt"
stamp done
