#!/bin/bash
# Issue 19, round D (after round C, same machine): the chain on 1, 2 and 16 cores with the CPU
# cull (fastest of 2) and with prt-cull --backend auto; old against new prt-cull (CPU) and prt-iso
# on the 1M room's pools, and prt-iso on a noisy scan, pinned to 16, 2 and 1 cores; section hashes.
set -uo pipefail
OUT=${OUT:-/tmp/out}
mkdir -p "$OUT"
exec > >(tee "$OUT/d.txt") 2>&1
B=build-dev/bin
KEEP=1 bash scripts/bench-preprocess.sh build-dev 1000000 1,2,16 2 > $OUT/chain-cpu.txt
cat $OUT/chain-cpu.txt
w=$(sed -n 's/^# work folder: //p' $OUT/chain-cpu.txt)
CULL_BACKEND=auto bash scripts/bench-preprocess.sh build-dev 1000000 2,16 2 > $OUT/chain-auto.txt
cat $OUT/chain-auto.txt
$B/prt-synth room --scan --range-noise 0.0005 --outliers 0.01 -o /tmp/scan.pool -q &&
    $B/prt-import /tmp/scan.pool -o /tmp/scan-imp.pool -q && $B/prt-radii /tmp/scan-imp.pool -o /tmp/scan-imp.pool -q
stats() {
    python3 -c "
import json; d = json.load(open('$1'))
print(' '.join(f'{k[8:]}={d[k]:.3f}' for k in ('seconds_tree','seconds_passive','seconds_balance','seconds_corners','seconds_closure','seconds_encode','seconds_total') if k in d))"
}
for t in 16 2 1; do
    for v in old new; do
        s0=$(date +%s.%N)
        taskset -c 0-$((t - 1)) /tmp/$v/prt-cull $w/prt-octree.pool -o /tmp/cull-$v.pool --backend cpu -q
        s1=$(date +%s.%N)
        taskset -c 0-$((t - 1)) /tmp/$v/prt-iso $w/prt-cull.pool -o /tmp/iso-$v.pool -q --stats-json /tmp/iso-$v.json
        s2=$(date +%s.%N)
        taskset -c 0-$((t - 1)) /tmp/$v/prt-iso /tmp/scan-imp.pool -o /tmp/scan-$v.pool -q --stats-json /tmp/scan-$v.json
        s3=$(date +%s.%N)
        echo "$v $t thr: room cull $(awk -v a=$s0 -v b=$s1 "BEGIN { printf \"%.3f\", b - a }") s, room iso $(awk -v a=$s1 -v b=$s2 "BEGIN { printf \"%.3f\", b - a }") s [$(stats /tmp/iso-$v.json)], scan iso $(awk -v a=$s2 -v b=$s3 "BEGIN { printf \"%.3f\", b - a }") s [$(stats /tmp/scan-$v.json)]"
    done
done
for p in cull iso scan; do
    for v in old new; do
        $B/prt-info --json /tmp/$p-$v.pool | python3 -c "
import hashlib, json, sys
d = json.load(sys.stdin); f = open('/tmp/$p-$v.pool', 'rb'); out = []
for s in d['sections']:
    if s['name'] == 'provenance': continue
    f.seek(s['offset']); out.append(s['name'] + ':' + hashlib.sha1(f.read(s['bytes'])).hexdigest()[:12])
print('$p $v', ' '.join(out))"
    done
done
