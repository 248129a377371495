#!/usr/bin/env bash
# Issue 19 on the GPU host (one H200, 16 Intel Xeon cores), 2026-12-01: prt-iso with its serial
# parts parallelized (this tree) against the tree before (base), on the preprocessing chain's 1M
# room (scripts/bench-preprocess.sh, CPU backends) and on a noisy synthetic room scan; the two
# prt-iso binaries alternate, pinned to 16, 2 and 1 cores (taskset); their pools are compared
# section by section (provenance aside).
# Carried in .ab/ (built on the dev VM, CPU only, build-dev configuration): base/bin and new/bin,
# each with prt-import, prt-radii, prt-octree, prt-cull, prt-iso, prt-info, prt-synth.
# Usage (repository root): [LOG=name] bash preprocess/bench/results/h200-2026-12-01-issue19-iso/gpu-i1.sh
# (gpu-i3.sh runs it again with LOG=i3 on the final prt-iso)
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/${LOG:-i1}.txt") 2>&1
nproc; grep -m1 "model name" /proc/cpuinfo; t0=$SECONDS; root=$PWD
for v in base new; do
  echo "== chain, $v"; KEEP=1 bash scripts/bench-preprocess.sh .ab/$v 1000000 2,16 2 | tee /tmp/chain-$v.txt
done
w=$(awk '/^# work folder:/{print $4}' /tmp/chain-new.txt)
B=$root/.ab/new/bin; cd /tmp
$B/prt-synth room --scan --range-noise 0.0005 --outliers 0.01 -o scan.pool -q && $B/prt-import scan.pool -o scan.pool -q &&
  $B/prt-radii scan.pool -o scan.pool -q || echo "scan pool failed"
secs() { python3 -c "import json; j=json.load(open('$1')); print(' '.join('%s %.3f' % (k[8:], j[k]) for k in ['seconds_tree','seconds_passive','seconds_balance','seconds_corners','seconds_closure','seconds_encode','seconds_total']))"; }
for t in 16 2 1; do
  rounds=3; [ $t = 1 ] && rounds=1
  for r in $(seq $rounds); do
    for v in base new; do
      for m in room scan; do
        in=$w/prt-cull.pool; [ $m = scan ] && in=/tmp/scan.pool
        s0=$(date +%s.%N); taskset -c 0-$((t - 1)) $root/.ab/$v/bin/prt-iso $in -o /tmp/$m-$v.pool -q --stats-json /tmp/$m-$v.json
        s1=$(date +%s.%N)
        echo "$m $v ${t}thr r$r wall $(awk -v a=$s0 -v b=$s1 'BEGIN{printf "%.3f", b-a}') [$(secs /tmp/$m-$v.json)]"
      done
    done
  done
done
for m in room scan; do
  for v in base new; do
    $B/prt-info --json /tmp/$m-$v.pool | python3 -c "
import json, sys, hashlib
d = json.load(sys.stdin); f = open('/tmp/$m-$v.pool', 'rb'); out = []
for s in d['sections']:
    if s['name'] == 'provenance': continue
    f.seek(s['offset']); out.append(s['name'] + ':' + hashlib.sha1(f.read(s['bytes'])).hexdigest()[:12])
print('$m $v', ' '.join(out))" > /tmp/h-$m-$v.txt
  done
  if diff <(cut -d' ' -f3- /tmp/h-$m-base.txt) <(cut -d' ' -f3- /tmp/h-$m-new.txt) >/dev/null; then
    echo "$m: pools equal section by section ($(wc -w < /tmp/h-$m-new.txt) words)"; else echo "$m: POOLS DIFFER"; cat /tmp/h-$m-*.txt; fi
done
echo "elapsed $((SECONDS - t0)) s"
