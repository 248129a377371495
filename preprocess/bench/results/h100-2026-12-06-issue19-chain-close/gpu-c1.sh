#!/usr/bin/env bash
# Issue 19, closing measurement of the preprocessing chain (c1): main's tools (cd2c4ed, build-cu
# packed in build-ab/chain.tar.xz: prt-import, prt-radii, prt-octree, prt-cull, prt-iso), on one
# GPU host, 2 and 16 cores, three runs per step, BACKEND=auto. Two rounds of
# scripts/bench-preprocess.sh with FRESH=1 (each run into a new file) around one without (each run
# after the first over the previous run's output, as every earlier measurement); then one chain on
# 16 cores with the tools' own reports (their phases), and what the disk costs: 150 MB written with
# fsync, then written over. (The call ran a draft of the script whose removal was unconditional,
# against cd2c4ed's script for the middle round: the same commands as these.)
# Carried: build-ab/chain.tar.xz.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/c1.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader; t0=$SECONDS
lscpu | grep -E "Model name|^CPU\(s\)|Thread\(s\) per core|Core\(s\) per socket"
df -T /tmp | tail -1
b=/tmp/chain; rm -rf $b; mkdir -p $b/bin
python3 -c "import tarfile, sys; tarfile.open(sys.argv[1]).extractall(sys.argv[2])" build-ab/chain.tar.xz $b/bin
echo "== round 1, FRESH=1 (into new files)"
FRESH=1 BACKEND=auto bash scripts/bench-preprocess.sh $b 1000000 2,16 3
echo "== FRESH=0 (over the previous output)"
BACKEND=auto bash scripts/bench-preprocess.sh $b 1000000 2,16 3
echo "== round 2, FRESH=1 (into new files)"
FRESH=1 BACKEND=auto bash scripts/bench-preprocess.sh $b 1000000 2,16 3
echo "== one chain on 16 cores, the tools' reports"
work=$(mktemp -d); KEEP=1 FRESH=1 BACKEND=auto bash scripts/bench-preprocess.sh $b 1000000 16 1 | grep "work folder" | tee $work/f
wf=$(awk '{print $4}' $work/f)
in=$wf/room.ply
for s in prt-import prt-radii prt-octree prt-cull prt-iso; do
  extra=(); { [ $s = prt-cull ] || [ $s = prt-radii ]; } && extra=(--backend auto)
  rm -f $wf/r-$s.pool; s0=$(date +%s.%N)
  taskset -c 0-15 $b/bin/$s $in -o $wf/r-$s.pool "${extra[@]}" 2>&1 | grep -v "%" | tail -6
  echo "$s wall $(awk -v a="$s0" -v b="$(date +%s.%N)" 'BEGIN{printf "%.3f", b-a}') s"
  in=$wf/r-$s.pool
done
echo "== the disk: 150 MB written with fsync into a new file, then over it (dd)"
rm -f /tmp/ddt; dd if=/dev/zero of=/tmp/ddt bs=1M count=150 conv=fsync 2>&1 | tail -1
dd if=/dev/zero of=/tmp/ddt.new bs=1M count=150 conv=fsync 2>&1 | tail -1
s0=$(date +%s.%N); mv /tmp/ddt.new /tmp/ddt; echo "rename over 150 MB: $(awk -v a="$s0" -v b="$(date +%s.%N)" 'BEGIN{printf "%.3f", b-a}') s"
rm -rf "$wf" /tmp/ddt
echo "ALL_DONE $((SECONDS - t0)) s"
