#!/usr/bin/env bash
# Issue 17, node boxes in bricks: Nsight Compute's per-line warp instructions of the bricked kernel
# on the prt-synth room's shadow frame, without box code (v0) and with both tests (v3), 3 blocks per SM.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/n4.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; t0=$SECONDS
rm -rf /tmp/ab; mkdir -p /tmp/ab; python3 -c "import tarfile; tarfile.open('build-ab/pack4.tar.xz').extractall('/tmp/ab')"
new=/tmp/ab/new; w=/tmp/n4; rm -rf $w; mkdir -p $w; q=--quiet
$new/prt-synth room -n 1000000 -o $w/room.pool $q && $new/prt-radii $w/room.pool -o $w/room.pool --backend cuda $q \
  && $new/prt-octree $w/room.pool -o $w/room.pool $q && $new/prt-cull $w/room.pool -o $w/room.pool $q \
  && $new/prt-bricks $w/room.pool -o $w/room-b.pool --keep-float $q || echo "pool failed"
NCU=/usr/local/cuda/bin/ncu
for v in v0 v3; do
  $NCU --section SourceCounters --section LaunchStats --section WarpStateStats --section MemoryWorkloadAnalysis --import-source yes -k regex:'render' --launch-skip 3 --launch-count 1 -f -o /tmp/src-$v /tmp/ab/$v/prt-bench --backend cuda $w/room-b.pool --bricks --scenarios shadow --frames 1 --warmup 3 -q > /tmp/ncu-$v.log 2>&1
  echo "ncu $v rc $? $((SECONDS - t0)) s"; tail -2 /tmp/ncu-$v.log
  $NCU -i /tmp/src-$v.ncu-rep --page source --csv --print-source cuda,sass 2>/dev/null | gzip -c > $out/sass-$v.csv.gz
  $NCU -i /tmp/src-$v.ncu-rep --page details --csv > $out/details-$v.csv 2>/dev/null
done
python3 build-ab/ncu_lines.py $out/sass-v0.csv.gz $out/sass-v3.csv.gz 70 > $out/lines.txt 2>&1; head -100 $out/lines.txt
echo "ALL_DONE $((SECONDS - t0)) s"
