#!/usr/bin/env bash
# Issue 19, MLS on the GPU (H200): the general kernel against MLS-only kernels at 1-4 blocks per SM,
# kd-trees built with other prt-mls settings, and Nsight Compute on the MLS primary frame.
# Binaries built on the dev VM (build-ab/pack1.tar.xz: base = the landed tree's tools and prt-bench,
# var = prt-bench with PRT_MLS_EXPERIMENT's MLS-only kernels).
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/m1.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; t0=$SECONDS
rm -rf /tmp/ab; mkdir -p /tmp/ab; python3 -c "import tarfile; tarfile.open('build-ab/pack1.tar.xz').extractall('/tmp/ab')"
b=/tmp/ab/p1/base; v=/tmp/ab/p1/var; w=/tmp/m1; rm -rf $w; mkdir -p $w; q=--quiet
$b/prt-bench --save-pool $w/room.pool --frames 1 --warmup 0 --scenarios primary --backend cuda $q > /dev/null
$b/prt-cull $w/room.pool -o $w/culled.pool $q && $b/prt-iso $w/culled.pool -o $w/surf.pool $q
$b/prt-mls $w/surf.pool -o $w/mls.pool $q
$b/prt-mls $w/surf.pool -o $w/mls-noenc.pool --no-encourage $q
$b/prt-mls $w/surf.pool -o $w/mls-ct4.pool --cost-traversal 4 $q
echo "pools $((SECONDS - t0)) s"
bench() {  # bench LABEL BIN ARGS...
  local label=$1 bin=$2; shift 2
  $bin/prt-bench --backend cuda --frames 20 --warmup 3 --surface mls --json $w/b.json "$@" > /dev/null 2> $w/err.txt \
    || { echo "$label failed: $(tail -2 $w/err.txt)"; return; }
  python3 - "$label" $w/b.json <<'PY'
import json, sys
j = json.load(open(sys.argv[2]))
print(sys.argv[1].ljust(24), ' '.join('%s %.4f' % (x['name'], x['grays_per_s']) for x in j['scenarios']), flush=True)
PY
}
for r in 1 2; do
  bench "base general" $b $w/mls.pool --scenarios primary,shadow
  for m in 1 2 3 4; do bench "var mls-only blocks $m" $v $w/mls.pool --scenarios primary,shadow --min-blocks $m; done
done
for p in noenc ct4; do
  bench "base general $p" $b $w/mls-$p.pool --scenarios primary,shadow
  bench "var blocks 2 $p" $v $w/mls-$p.pool --scenarios primary,shadow --min-blocks 2
done
echo "bench $((SECONDS - t0)) s"
NCU=/usr/local/cuda/bin/ncu
for x in base var; do
  bin=$b; extra=""; [ $x = var ] && { bin=$v; extra="--min-blocks 2"; }
  $NCU --section SourceCounters --section LaunchStats --section Occupancy --section WarpStateStats --section MemoryWorkloadAnalysis --section ComputeWorkloadAnalysis --section SpeedOfLight --import-source yes -k regex:'render' --launch-skip 2 --launch-count 1 -f -o /tmp/src-$x $bin/prt-bench --backend cuda $w/mls.pool --surface mls --scenarios primary --frames 1 --warmup 2 $extra -q > /tmp/ncu-$x.log 2>&1
  echo "ncu $x rc $? $((SECONDS - t0)) s"; tail -2 /tmp/ncu-$x.log
  $NCU -i /tmp/src-$x.ncu-rep --page source --csv --print-source cuda,sass 2>/dev/null | gzip -c > $out/sass-$x.csv.gz
  $NCU -i /tmp/src-$x.ncu-rep --page details --csv > $out/details-$x.csv 2>/dev/null
  $NCU -i /tmp/src-$x.ncu-rep --page details 2>/dev/null | grep -E "Duration|Registers|Achieved Occupancy|Theoretical Occupancy|Warp Cycles Per Issued|Avg. Active Threads|Avg. Not Predicated|Memory Throughput|L1/TEX Hit|L2 Hit|Compute \(SM\) Throughput|Local|Stall|Issued Ipc|Executed Ipc" | head -40
done
python3 build-ab/ncu_lines.py $out/sass-base.csv.gz $out/sass-var.csv.gz 60 > $out/lines.txt 2>&1; head -80 $out/lines.txt
echo "ALL_DONE $((SECONDS - t0)) s"
