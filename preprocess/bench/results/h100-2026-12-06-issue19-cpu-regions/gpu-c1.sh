#!/usr/bin/env bash
# Issue 19 on the GPU host (16 cores), 2026-12-06, the landed tree (ad87488): the CPU backend against
# Embree 3 on the culled 1M room since the macro-regions (2026-12-05; the walk's default), 16 threads
# (512^2, 1024^2) and 2 threads pinned (512^2), two rounds; frames in turns, ours / Embree the median
# frame pair (prt-bench-embree). Carried: build-ab/eb.tar.xz (prt-bench-embree, prt-bench and prt-cull
# built on the dev VM without CUDA; Debian 12's libembree3.so.3 and libtbb.so.12). NAME (default c1)
# names the log and the JSON archive: later calls run this script on later trees.
set -uo pipefail
name=${NAME:-c1}
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/$name.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; nproc; grep -m1 "model name" /proc/cpuinfo
t0=$SECONDS; root=$PWD; w=/tmp/wc; rm -rf $w; mkdir -p $w/json
python3 -c "import tarfile; tarfile.open('build-ab/eb.tar.xz').extractall('$w')"
cd $w; export LD_LIBRARY_PATH=$w/lib
bin/prt-bench --backend cpu --synthetic 1000000 --save-pool room.pool --frames 1 --warmup 0 --width 64 --height 64 \
  --scenarios primary --quiet >/dev/null && bin/prt-cull room.pool -o room_c.pool --quiet || echo "pool failed"
sed 's/"room.pool"/"room_c.pool"/' $root/preprocess/bench/bench_room.json > scene.json
run() {  # round, threads, size, taskset cpus
  local pre=""; [ -n "$4" ] && pre="taskset -c $4"
  echo -n "r$1 th=$2 $3: "
  $pre bin/prt-bench-embree room_c.pool --scene scene.json --width $3 --height $3 \
    --frames 5 --warmup 1 --threads $2 --quiet --json $w/json/r$1-$2-$3.json 2>&1 |
    awk '/^(primary|shadow|reflect4) +[0-9]/{printf "%s %s/%s ms r=%s  ", $1, $2, $3, $6} /hits compared/{print ""; print}'
  echo
}
for r in 1 2; do run $r 16 512 ""; run $r 16 1024 ""; run $r 2 512 0,1; done
tar czf $out/$name-embree-json.tgz -C $w json
echo "ALL_DONE $((SECONDS - t0)) s"
