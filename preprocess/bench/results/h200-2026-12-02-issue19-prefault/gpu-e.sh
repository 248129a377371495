#!/usr/bin/env bash
# Issue 19 on the GPU host (16 Intel Xeon cores), 2026-12-02: prt-iso's step 6-7 serial passes in
# parallel (kept ancestors marked by atomic exchange, the depth-first leaf order as a parallel sort of
# the leaves' Morton codes, the node pool level by level) (new) against the tree before them (mid:
# the first-touch change). CPU binaries built on the dev VM, carried in build-ab/{mid,new}/bin; the
# chain's pools made here with CPU backends. The two prt-iso alternate; pools are compared.
# Usage (repository root, build-ab carried): bash <this script>
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/e1.txt") 2>&1
nproc; grep -m1 "model name" /proc/cpuinfo; t0=$SECONDS
for v in mid new; do mkdir -p /tmp/ab/$v/bin; cp build-ab/new/bin/* /tmp/ab/$v/bin/; done
cp build-ab/mid/bin/prt-iso /tmp/ab/mid/bin/
BACKEND=cpu KEEP=1 bash scripts/bench-preprocess.sh /tmp/ab/new 1000000 16 1 | tee /tmp/chain.txt
w=$(awk '/^# work folder:/{print $4}' /tmp/chain.txt)
B=/tmp/ab/new/bin; cd /tmp
$B/prt-synth room --scan --range-noise 0.0005 --outliers 0.01 -o scan.pool -q && $B/prt-import scan.pool -o scan.pool -q &&
  $B/prt-radii scan.pool -o scan.pool -q || echo "scan pool failed"
secs() { python3 -c "import json; j=json.load(open('$1')); print(' '.join('%s %.3f' % (k[8:], j[k]) for k in ['seconds_closure','seconds_encode','seconds_total']))"; }
for t in 16 2; do for r in 1 2 3 4; do for v in mid new; do for m in room scan; do
  in=$w/prt-cull.pool; [ $m = scan ] && in=/tmp/scan.pool
  s0=$(date +%s.%N)
  taskset -c 0-$((t - 1)) /tmp/ab/$v/bin/prt-iso $in -o /tmp/$m-$v.pool -q --stats-json /tmp/$m-$v.json
  s1=$(date +%s.%N)
  echo "$m $v ${t}thr r$r wall $(awk -v a=$s0 -v b=$s1 'BEGIN{printf "%.3f", b-a}') [$(secs /tmp/$m-$v.json)]"
done; done; done; done
cd $OLDPWD
python3 - <<'PY'
import sys; sys.path.insert(0, 'scripts/lib'); import prt_provenance as p
for m in ['room', 'scan']:
    a = p.read_checksums('/tmp/%s-mid.pool' % m); b = p.read_checksums('/tmp/%s-new.pool' % m)
    print(m, 'prt-iso pools equal section by section:', all(a[k] == b.get(k) for k in a if k != 1), len(a), 'sections')
PY
echo "ALL_DONE $((SECONDS - t0)) s"
