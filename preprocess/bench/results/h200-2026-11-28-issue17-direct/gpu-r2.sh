#!/bin/bash
# Issue 17: where the bricked kernel's time goes (ncu, one primary frame of the culled 1M room: float
# octree against direct bricks), then the GPU tests on this tree.
set -uo pipefail
OUT=${OUT:-/tmp/out}; mkdir -p "$OUT"; exec > >(tee "$OUT/r2.txt") 2>&1
nvidia-smi --query-gpu=name --format=csv,noheader
t0=$SECONDS
w=/tmp/w; bin=build-dev/bin
[ -f $w/room-smaller.pool ] || echo "no pools: run gpu-r1.sh first"
NCU=/usr/local/cuda/bin/ncu
M=gpu__time_duration.sum,smsp__inst_executed.sum,smsp__thread_inst_executed.sum,launch__registers_per_thread,launch__stack_size,launch__occupancy_limit_registers,sm__warps_active.avg.pct_of_peak_sustained_active,l1tex__t_sectors_pipe_lsu_mem_global_op_ld.sum,l1tex__t_sectors_pipe_lsu_mem_local_op_ld.sum,l1tex__t_sectors_pipe_lsu_mem_local_op_st.sum,l1tex__t_sector_hit_rate.pct,lts__t_sector_hit_rate.pct,smsp__inst_executed_op_global_ld.sum,smsp__inst_executed_op_local_ld.sum,smsp__sass_inst_executed_op_branch.sum,smsp__average_warp_latency_issue_stalled_long_scoreboard.ratio,smsp__average_warp_latency_issue_stalled_lg_throttle.ratio,smsp__average_warp_latency_issue_stalled_wait.ratio,smsp__average_warp_latency_issue_stalled_math_pipe_throttle.ratio,smsp__average_warp_latency_issue_stalled_no_instruction.ratio,smsp__average_warp_latency_issue_stalled_short_scoreboard.ratio,smsp__average_warp_latency_issue_stalled_barrier.ratio,smsp__average_warp_latency_issue_stalled_mio_throttle.ratio,smsp__average_warp_latency_issue_stalled_not_selected.ratio,smsp__average_warp_latency_issue_stalled_selected.ratio,smsp__average_warp_latency_issue_stalled_dispatch_stall.ratio,smsp__average_warp_latency_issue_stalled_branch_resolving.ratio,smsp__pipe_fma_cycles_active.avg.pct_of_peak_sustained_active,smsp__pipe_alu_cycles_active.avg.pct_of_peak_sustained_active,smsp__inst_executed_pipe_xu.sum,smsp__issue_active.avg.pct_of_peak_sustained_active
for mode in float smaller; do
  extra="--bricks"; [ $mode = float ] && extra=""
  $NCU --metrics $M -k regex:'render' --launch-skip 3 --launch-count 1 --csv --print-units base $bin/prt-bench --backend cuda $w/room-smaller.pool $extra --scenarios primary --frames 1 --warmup 3 -q >$OUT/ncu-room-$mode.csv 2>$OUT/ncu-$mode.err
  echo "ncu $mode rc $?"
done
python3 - $OUT/ncu-room-float.csv $OUT/ncu-room-smaller.csv <<'PY'
import csv, sys
def load(p):
    rows = [r for r in csv.reader(open(p)) if len(r) > 5]
    h = rows[0]; i_name = h.index('Metric Name'); i_val = h.index('Metric Value'); i_k = h.index('Kernel Name')
    return {r[i_name]: r[i_val] for r in rows[1:]}, rows[1][i_k] if len(rows) > 1 else '?'
a, ka = load(sys.argv[1]); b, kb = load(sys.argv[2])
print('kernels:', ka[:60], '|', kb[:60])
for k in sorted(set(a) | set(b)): print(k.ljust(75), a.get(k, '-').rjust(16), b.get(k, '-').rjust(16))
PY
echo "ncu at $((SECONDS - t0)) s"
cmake --build build-dev -j16 --target prt_runtime_gpu_tests prt_stability_gpu_tests prt_brick_stream_gpu_tests prt_iso_gpu_tests prt_patches_gpu_tests prt_cull_gpu_tests >/tmp/b2.txt 2>&1 || { grep -E "error" /tmp/b2.txt | head -20; }
echo "built tests at $((SECONDS - t0)) s"
(cd build-dev && ctest -L gpu -E "Window|python|Photons|LightMap|MlsGpu" --timeout 200 --output-on-failure > $OUT/ctest.txt 2>&1; grep -E "tests passed|Failed|FAILED|Not Run|\*\*\*" $OUT/ctest.txt | head -30)
echo "ALL_DONE $((SECONDS - t0)) s"
