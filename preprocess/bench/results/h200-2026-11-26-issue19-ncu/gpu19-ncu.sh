#!/bin/bash
# Issue 19, "measure first": Nsight Compute on the render megakernel, 1M-point synthetic room
# (prt-bench default), primary and reflect4 frames at 1024x1024, after prt-bench's own timings.
# Run from the repository root by the device tool (.device-deps carried); writes under $OUT.
set -uo pipefail
OUT=${OUT:-/tmp/out}
mkdir -p "$OUT"
exec > >(tee "$OUT/log.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version,clocks.max.sm,clocks.max.mem --format=csv
t0=$(date +%s)
cmake -S . -B build-dev -DCMAKE_PREFIX_PATH=$PWD/.device-deps/usr -DPRT_WITH_PCL=OFF -DPRT_WITH_OPENMESH=OFF \
    -DPRT_WITH_OIIO=OFF -DPRT_WITH_PYTHON=OFF -DPRT_WITH_GLFW=OFF -DCMAKE_BUILD_TYPE=Release >"$OUT/cmake.txt" 2>&1 ||
    { tail -30 "$OUT/cmake.txt"; exit 1; }
cmake --build build-dev -j16 --target prt-bench >"$OUT/build.txt" 2>&1 || { tail -30 "$OUT/build.txt"; exit 1; }
echo "build: $(( $(date +%s) - t0 )) s"
B=build-dev/bin/prt-bench
$B --save-pool /tmp/room1m.pool --scenarios primary,shadow,reflect4,full4 --json "$OUT/bench-room1m.json" 2>&1 | tail -20
NCU=/usr/local/cuda/bin/ncu
for sc in primary reflect4; do
    $NCU --set full --target-processes all -k regex:'render|trace|shade|cast' --launch-count 2 \
        -o "$OUT/ncu-room1m-$sc" -f $B /tmp/room1m.pool --scenarios $sc --frames 1 --warmup 0 -q >"$OUT/ncu-$sc-run.txt" 2>&1
    tail -5 "$OUT/ncu-$sc-run.txt"
    $NCU --import "$OUT/ncu-room1m-$sc.ncu-rep" --page details --print-units base >"$OUT/ncu-room1m-$sc-details.txt" 2>&1
    $NCU --import "$OUT/ncu-room1m-$sc.ncu-rep" --page raw --csv \
        --metrics launch__registers_per_thread,launch__occupancy_limit_registers,sm__warps_active.avg.pct_of_peak_sustained_active,smsp__thread_inst_executed_per_inst_executed.ratio,dram__throughput.avg.pct_of_peak_sustained_elapsed,lts__t_sector_hit_rate.pct,l1tex__t_sector_hit_rate.pct,sm__throughput.avg.pct_of_peak_sustained_elapsed,gpu__time_duration.sum,local_load_bytes,smsp__inst_executed.sum \
        >"$OUT/ncu-room1m-$sc-raw.csv" 2>&1
done
ls -la "$OUT"
