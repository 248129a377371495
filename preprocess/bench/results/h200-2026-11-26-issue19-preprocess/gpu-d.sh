#!/bin/bash
# Issue 19, round D: prt-iso with the parallel 2:1 balance and closure prefilter (new) against
# the landed iso_build.cpp (old, carried as .device-deps/old_iso_build.cpp): every section but the
# provenance must be byte-equal on each model, at 16 and 1 threads; step times; then the chain.
set -uo pipefail
OUT=${OUT:-/tmp/out}
mkdir -p "$OUT"
exec > >(tee "$OUT/d.txt") 2>&1
flags="-DCMAKE_PREFIX_PATH=$PWD/.device-deps/usr -DPRT_WITH_PCL=OFF -DPRT_WITH_OPENMESH=OFF -DPRT_WITH_OIIO=OFF -DPRT_WITH_PYTHON=OFF -DPRT_WITH_GLFW=OFF -DCMAKE_BUILD_TYPE=Release"
t0=$SECONDS
cmake -S . -B build-dev $flags >/tmp/d.cmake.txt 2>&1 &&
    cmake --build build-dev -j16 --target prt-import prt-radii prt-octree prt-cull prt-iso prt-synth prt-info >/tmp/d.build.txt 2>&1 ||
    { grep -E "error" -A3 /tmp/d.build.txt | head -30; exit 1; }
echo "build: $((SECONDS - t0)) s"
cp build-dev/bin/prt-iso /tmp/iso-new
cp preprocess/iso/iso_build.cpp /tmp/new_iso_build.cpp
cp .device-deps/old_iso_build.cpp preprocess/iso/iso_build.cpp
cmake --build build-dev -j16 --target prt-iso >/tmp/d.build2.txt 2>&1 || { grep error -A3 /tmp/d.build2.txt | head; exit 1; }
cp build-dev/bin/prt-iso /tmp/iso-old
cp /tmp/new_iso_build.cpp preprocess/iso/iso_build.cpp
echo "old build: $((SECONDS - t0)) s"
B=build-dev/bin
w=/tmp/models; mkdir -p $w
$B/prt-synth sphere -n 200000 -o $w/sphere.pool -q && $B/prt-radii $w/sphere.pool -o $w/sphere.pool -q
$B/prt-synth torus -n 300000 -o $w/torus.pool -q && $B/prt-radii $w/torus.pool -o $w/torus.pool -q
$B/prt-synth room --scan --range-noise 0.0005 --outliers 0.01 -o $w/scan.pool -q &&
    $B/prt-import $w/scan.pool -o $w/scan-imp.pool -q && $B/prt-radii $w/scan-imp.pool -o $w/scan-imp.pool -q
KEEP=1 bash scripts/bench-preprocess.sh build-dev 1000000 16 1 > $OUT/pre16.txt
cp $(sed -n 's/^# work folder: //p' $OUT/pre16.txt)/prt-radii.pool $w/room1m.pool
hashes() {  # every section but the provenance: name and xxh-like digest (sha1)
    $B/prt-info --json "$1" | python3 -c "
import hashlib, json, sys
d = json.load(sys.stdin); f = open('$1', 'rb'); out = []
for s in d['sections']:
    if s['name'] == 'provenance': continue
    f.seek(s['offset']); out.append(s['name'] + ':' + hashlib.sha1(f.read(s['bytes'])).hexdigest()[:12])
print(' '.join(out))"
}
for m in sphere torus scan-imp room1m; do
    for v in old new; do
        for t in 16 1; do
            [ $v = old ] && [ $t = 1 ] && continue
            taskset -c 0-$((t - 1)) /tmp/iso-$v $w/$m.pool -o $w/$m-$v-$t.iso.pool -q --stats-json $OUT/$m-$v-$t.json || echo "FAILED $m $v $t"
            python3 -c "
import json; d = json.load(open('$OUT/$m-$v-$t.json'))
print('$m $v $t thr:', 'leaves', d['leaves'], 'balance_splits', d['balance_splits'], 'closure_leaves', d['closure_leaves'],
      ' '.join(f'{k[8:]}={d[k]:.3f}' for k in ('seconds_tree','seconds_balance','seconds_corners','seconds_closure','seconds_encode','seconds_total')))"
            hashes $w/$m-$v-$t.iso.pool > $OUT/$m-$v-$t.hash
        done
    done
    if cmp -s $OUT/$m-old-16.hash $OUT/$m-new-16.hash && cmp -s $OUT/$m-old-16.hash $OUT/$m-new-1.hash; then
        echo "$m: EQUAL sections"
    else
        echo "$m: DIFFERENT"; cat $OUT/$m-old-16.hash $OUT/$m-new-16.hash $OUT/$m-new-1.hash
    fi
done
bash scripts/bench-preprocess.sh build-dev 1000000 1,2,16 2 | tee $OUT/preprocess.txt
echo "ALL_DONE $((SECONDS - t0)) s"
