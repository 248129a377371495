#!/bin/bash
# Issue 19: the 1d5102d regression. Builds today's prt-bench and 81d1185's side by side, saves each
# one's synthetic room pool, renders each pool with each binary, and counts the kernel's work (ncu).
set -uo pipefail
OUT=${OUT:-/tmp/out}
mkdir -p "$OUT"
exec > >(tee "$OUT/r1.txt") 2>&1
nvidia-smi --query-gpu=name,clocks.sm,clocks.max.sm --format=csv,noheader
nproc
F="-DCMAKE_PREFIX_PATH=$PWD/.device-deps/usr -DPRT_WITH_PCL=OFF -DPRT_WITH_OPENMESH=OFF -DPRT_WITH_OIIO=OFF -DPRT_WITH_PYTHON=OFF -DPRT_WITH_GLFW=OFF -DCMAKE_BUILD_TYPE=Release"
t0=$SECONDS
[ -x build-dev/bin/prt-bench ] || ( cmake -S . -B build-dev $F >/tmp/cur.cmake.txt 2>&1 && cmake --build build-dev -j8 --target prt-bench >/tmp/cur.build.txt 2>&1 || tail -20 /tmp/cur.build.txt ) & p1=$!
[ -x /tmp/v81/build/bin/prt-bench ] || ( mkdir -p /tmp/v81 && tar -xzf .device-deps/old/81d1185.tar.gz -C /tmp/v81 && cmake -S /tmp/v81 -B /tmp/v81/build $F >/tmp/old.cmake.txt 2>&1 &&
  cmake --build /tmp/v81/build -j8 --target prt-bench >/tmp/old.build.txt 2>&1 || tail -20 /tmp/old.build.txt ) & p2=$!
wait $p1 $p2
echo "built in $((SECONDS - t0)) s"
NEW=build-dev/bin/prt-bench
OLD=/tmp/v81/build/bin/prt-bench
$NEW --save-pool /tmp/new.pool --scenarios primary --frames 5 -q >/dev/null 2>&1; echo "new save rc $?"
$OLD --save-pool /tmp/old.pool --scenarios primary --frames 5 -q >/dev/null 2>&1; echo "old save rc $?"
ls -la /tmp/*.pool
summ() { python3 -c "
import json,sys; d = json.load(open('$1'))
print('$2', [(s.get('name'), round(s['grays_per_s'], 3), round(s.get('leaves_per_ray', 0), 2), round(s.get('splat_tests_per_ray', 0), 2)) for s in d['scenarios']])" 2>&1 | tail -1; }
for round in 1 2; do
  for bin in NEW OLD; do
    for pool in new old; do
      B=${!bin}
      rm -f /tmp/r.json
      $B /tmp/$pool.pool --scenarios primary,shadow --frames 50 -q --json /tmp/r.json >/tmp/run.txt 2>&1 || tail -2 /tmp/run.txt
      summ /tmp/r.json "bin=$bin pool=$pool r$round"
    done
  done
  rm -f /tmp/r.json; $NEW /tmp/new.pool --kernel mega-static --scenarios primary,shadow --frames 50 -q --json /tmp/r.json >/dev/null 2>&1
  summ /tmp/r.json "bin=NEW-static pool=new r$round"
done
NCU=/usr/local/cuda/bin/ncu
M=gpu__time_duration.sum,smsp__inst_executed.sum,smsp__thread_inst_executed.sum,launch__registers_per_thread,launch__grid_size,launch__block_size,launch__stack_size,l1tex__t_sectors_pipe_lsu_mem_global_op_ld.sum,l1tex__t_requests_pipe_lsu_mem_global_op_ld.sum,l1tex__t_sectors_pipe_lsu_mem_local_op_ld.sum,l1tex__t_sectors_pipe_lsu_mem_local_op_st.sum,l1tex__t_sector_hit_rate.pct,lts__t_sector_hit_rate.pct,sm__warps_active.avg.pct_of_peak_sustained_active,smsp__inst_executed_op_global_ld.sum,smsp__inst_executed_op_local_ld.sum,smsp__inst_executed_op_local_st.sum,smsp__sass_inst_executed_op_branch.sum
for bin in NEW OLD; do
  B=${!bin}
  $NCU --metrics $M -k regex:'render' --launch-skip 3 --launch-count 1 --csv --print-units base $B /tmp/new.pool --scenarios primary --frames 1 --warmup 3 -q >$OUT/ncu-$bin.csv 2>$OUT/ncu-$bin.err
  echo "ncu $bin rc $?"
done
( mkdir -p $OUT/sass; /usr/local/cuda/bin/cuobjdump -lelf $NEW | head -3 ) 2>&1 | tail -3
echo "ALL_DONE $((SECONDS - t0)) s"
