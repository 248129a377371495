#!/usr/bin/env bash
# Issues 17 / 19 on the GPU host (one H200, 16 cores), 2026-12-04, the landed tree (1426f45):
# 1. the CPU backend against Embree 3 on the culled 1M room since the node boxes (2026-12-03), 16
#    threads (512^2, 1024^2) and 2 threads pinned (512^2), two rounds;
# 2. the out-of-core build's memory traffic with the kernel: the 100M room from points with glibc's
#    default (large blocks are mmap'd and unmapped, each cell's arrays faulted in and zeroed again)
#    against GLIBC_TUNABLES that keep freed memory in the heap (mmap_max=0, no trimming), alternating.
# Carried: build-ab/pack.tar.xz (the landed tools, CUDA), build-ab/eb (prt-bench-embree built on the
# dev VM without CUDA, Debian 12's libembree3.so.3 and libtbb.so.12).
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/a1.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; nproc; grep -m1 "model name" /proc/cpuinfo
uname -r; cat /sys/kernel/mm/transparent_hugepage/enabled /sys/kernel/mm/transparent_hugepage/defrag
t0=$SECONDS; root=$PWD
rm -rf /tmp/ab; mkdir -p /tmp/ab; python3 -c "import tarfile; tarfile.open('build-ab/pack.tar.xz').extractall('/tmp/ab')"
bin=/tmp/ab/bin; w=/tmp/wa; mkdir -p $w/json
python3 -c "import tarfile; tarfile.open('build-ab/eb/lib.tar.xz').extractall('$w')"
cd $w
$bin/prt-bench --backend cpu --synthetic 1000000 --save-pool room.pool --frames 1 --warmup 0 --width 64 --height 64 \
  --scenarios primary --quiet >/dev/null && $bin/prt-cull room.pool -o room_c.pool --quiet || echo "pool failed"
sed 's/"room.pool"/"room_c.pool"/' $root/preprocess/bench/bench_room.json > scene.json
run() {  # round, threads, size, taskset cpus
  local pre=""; [ -n "$4" ] && pre="taskset -c $4"
  echo -n "r$1 th=$2 $3: "
  LD_LIBRARY_PATH=$w/lib $pre $root/build-ab/eb/bin/prt-bench-embree room_c.pool --scene scene.json --width $3 --height $3 \
    --frames 5 --warmup 1 --threads $2 --quiet --json $w/json/r$1-$2-$3.json 2>&1 |
    awk '/^(primary|shadow|reflect4) +[0-9]/{printf "%s %s/%s ms r=%s  ", $1, $2, $3, $6}'
  echo
}
for r in 1 2; do run $r 16 512 ""; run $r 16 1024 ""; run $r 2 512 0,1; done
tar czf $out/a1-embree-json.tgz -C $w json
echo "embree done $((SECONDS - t0)) s"
rm -f room.pool
$bin/prt-synth room -n 100000000 -o $w/s100.pool --quiet || echo "synth failed"
echo "synth done $((SECONDS - t0)) s"
keep="glibc.malloc.mmap_max=0:glibc.malloc.trim_threshold=1099511627776"
for r in 1 2; do
  for mode in default keep; do
    env=""; [ $mode = keep ] && env="GLIBC_TUNABLES=$keep"
    echo -n "r$r $mode: "
    env $env /usr/bin/time -f "%e s wall, %U s user, %S s sys, peak RSS %M KB, %R minor faults" \
      $bin/prt-bricks $w/s100.pool -o $w/b100.pool --memory 12G --quiet --stats-json $w/st.json 2>&1 | tr '\n' ' '
    python3 -c "
import json; s = json.load(open('$w/st.json'))
print(' build %.1f s, %.2fM pts/s; summed: octree %.1f cull %.1f bricks %.1f partition %.1f assemble %.1f' % (s['build_seconds'], s['points_per_second'] / 1e6, s['seconds']['octree'], s['seconds']['cull'], s['seconds']['bricks'], s['seconds']['partition'], s['seconds']['assemble']))"
    rm -f $w/b100.pool
  done
done
echo "ALL_DONE $((SECONDS - t0)) s"
