#!/usr/bin/env bash
# Issue 19 on the GPU host (one H200, 16 Intel Xeon cores), 2026-12-02: the large tables' first
# touch in parallel (pre::prefault, resize_prefaulted, reserve_prefaulted: prt-iso's nodes, corner
# tables and leaves, prt-octree's build records, sorted copy and stored splats) (new) against the
# landed tools (base). prt-iso and prt-octree were built on the dev VM (CPU only, build-dev) and
# carried in build-ab/{base,new}/bin; the other tools of the chain are built here with CUDA, so the
# chain runs as a GPU-host user runs it (BACKEND=auto: prt-radii and prt-cull on the GPU). The two
# variants alternate; pools are compared section by section. prt-cull's own timing (stats JSON) at
# 2 and 16 threads shows what its 0.6 s are.
# Usage (repository root, .device-deps and build-ab carried): LOG=p1 bash <this script>
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/${LOG:-p1}.txt") 2>&1
nproc; grep -m1 "model name" /proc/cpuinfo; nvidia-smi --query-gpu=name --format=csv,noheader
echo "THP: $(cat /sys/kernel/mm/transparent_hugepage/enabled) defrag: $(cat /sys/kernel/mm/transparent_hugepage/defrag)"
t0=$SECONDS; root=$PWD
cmake -S . -B /tmp/bc -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=$root/.device-deps/usr \
  -DPRT_BUILD_TESTS=OFF -DCMAKE_CUDA_ARCHITECTURES=90 >/tmp/cfg.log 2>&1 || { tail -20 /tmp/cfg.log; exit 1; }
cmake --build /tmp/bc -j 16 --target prt-import prt-radii prt-octree prt-cull prt-info prt-synth >/tmp/b.log 2>&1 ||
  { tail -30 /tmp/b.log; exit 1; }
echo "build done $((SECONDS - t0)) s"
for v in base new; do
  mkdir -p /tmp/ab/$v/bin; cp /tmp/bc/bin/* /tmp/ab/$v/bin/; cp build-ab/$v/bin/* /tmp/ab/$v/bin/
done
for r in 1 2 3; do for v in base new; do
  echo "== chain, auto, $v, round $r"
  BACKEND=auto KEEP=1 bash scripts/bench-preprocess.sh /tmp/ab/$v 1000000 2,16 2 | tee /tmp/chain-$v.txt
done; done
w=$(awk '/^# work folder:/{print $4}' /tmp/chain-new.txt)
for t in 2 16; do for r in 1 2; do
  taskset -c 0-$((t - 1)) /tmp/ab/new/bin/prt-cull $w/prt-octree.pool -o /tmp/cull-$t.pool -q --backend auto --stats-json /tmp/cull-$t.json
  python3 -c "import json; j=json.load(open('/tmp/cull-$t.json')); print('prt-cull ${t}thr r$r', j['device'], 'cull %.3f total %.3f' % (j['cull_seconds'], j['total_seconds']))"
done; done
B=/tmp/ab/new/bin; cd /tmp
$B/prt-synth room --scan --range-noise 0.0005 --outliers 0.01 -o scan.pool -q && $B/prt-import scan.pool -o scan.pool -q &&
  $B/prt-radii scan.pool -o scan.pool -q || echo "scan pool failed"
secs() { python3 -c "import json; j=json.load(open('$1')); print(' '.join('%s %.3f' % (k[8:], j[k]) for k in ['seconds_tree','seconds_passive','seconds_balance','seconds_corners','seconds_closure','seconds_encode','seconds_total']))"; }
for t in 2 16; do for r in 1 2 3; do for v in base new; do for m in room scan; do
  in=$w/prt-cull.pool; [ $m = scan ] && in=/tmp/scan.pool
  s0=$(date +%s.%N)
  tm=(); [ -x /usr/bin/time ] && tm=(/usr/bin/time -f "%S %R" -o /tmp/tm); echo "- -" >/tmp/tm
  "${tm[@]}" taskset -c 0-$((t - 1)) /tmp/ab/$v/bin/prt-iso $in -o /tmp/$m-$v.pool -q --stats-json /tmp/$m-$v.json
  s1=$(date +%s.%N)
  echo "$m $v ${t}thr r$r wall $(awk -v a=$s0 -v b=$s1 'BEGIN{printf "%.3f", b-a}') sys,faults $(tr '\n' ' ' </tmp/tm)[$(secs /tmp/$m-$v.json)]"
done; done; done; done
hashes() {  # section name:sha1 of pool $1, provenance aside
  $B/prt-info --json "$1" | python3 -c "
import json, sys, hashlib
d = json.load(sys.stdin); f = open('$1', 'rb'); out = []
for s in d['sections']:
    if s['name'] == 'provenance': continue
    f.seek(s['offset']); out.append(s['name'] + ':' + hashlib.sha1(f.read(s['bytes'])).hexdigest()[:12])
print(' '.join(out))"; }
same() {  # label, pool a, pool b
  if [ "$(hashes "$2")" = "$(hashes "$3")" ]; then echo "$1: pools equal section by section ($(hashes "$3" | wc -w) sections)"
  else echo "$1: POOLS DIFFER"; hashes "$2"; hashes "$3"; fi; }
wb=$(awk '/^# work folder:/{print $4}' /tmp/chain-base.txt)
for s in prt-octree prt-iso; do same "chain $s" $wb/$s.pool $w/$s.pool; done
for m in room scan; do same "$m prt-iso" /tmp/$m-base.pool /tmp/$m-new.pool; done
echo "ALL_DONE $((SECONDS - t0)) s"
