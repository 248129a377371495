#!/bin/bash
# Issue 19, round B (after round A, same machine): the chain on 1, 2 and 16 cores with the CPU
# cull (fastest of 2), the chain as a GPU-machine user runs it (prt-cull --backend auto), and old
# against new prt-cull (CPU) and prt-iso on the same pools, pinned to 1, 2 and 16 cores.
set -uo pipefail
OUT=${OUT:-/tmp/out}
mkdir -p "$OUT"
exec > >(tee "$OUT/b.txt") 2>&1
KEEP=1 bash scripts/bench-preprocess.sh build-dev 1000000 1,2,16 2 > $OUT/chain-cpu.txt
cat $OUT/chain-cpu.txt
w=$(sed -n 's/^# work folder: //p' $OUT/chain-cpu.txt)
CULL_BACKEND=auto bash scripts/bench-preprocess.sh build-dev 1000000 2,16 1 > $OUT/chain-auto.txt
cat $OUT/chain-auto.txt
for t in 16 2 1; do
    for v in old new; do
        s0=$(date +%s.%N)
        taskset -c 0-$((t - 1)) /tmp/$v/prt-cull $w/prt-octree.pool -o /tmp/cull-$v.pool --backend cpu -q
        s1=$(date +%s.%N)
        taskset -c 0-$((t - 1)) /tmp/$v/prt-iso $w/prt-cull.pool -o /tmp/iso-$v.pool -q --stats-json /tmp/iso-$v.json
        s2=$(date +%s.%N)
        python3 -c "
import json; d = json.load(open('/tmp/iso-$v.json'))
print('$v $t thr: cull %.3f s, iso %.3f s;' % ($s1 - $s0, $s2 - $s1), 'iso build', ' '.join(f'{k[8:]}={d[k]:.3f}' for k in ('seconds_tree','seconds_passive','seconds_balance','seconds_corners','seconds_closure','seconds_encode','seconds_total') if k in d))"
    done
done
for p in cull iso; do
  for v in old new; do
    build-dev/bin/prt-info --json /tmp/$p-$v.pool | python3 -c "
import hashlib, json, sys
d = json.load(sys.stdin); f = open('/tmp/$p-$v.pool', 'rb'); out = []
for s in d['sections']:
    if s['name'] == 'provenance': continue
    f.seek(s['offset']); out.append(s['name'] + ':' + hashlib.sha1(f.read(s['bytes'])).hexdigest()[:12])
print('$p $v', ' '.join(out))"
  done
done
