#!/usr/bin/env bash
# Issue 17 (H200): in-core bricks before and after streamed prefixes and leaf stops (prt-bench of
# c8873be against this tree's), alternating, three rounds: the culled 1M room (bench_room.json),
# float and bricks (--lod-splats 32 and 12).
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/r4.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; t0=$SECONDS
rm -rf /tmp/ab; mkdir -p /tmp/ab
for p in pack10 pack26 pack23b; do python3 -c "import tarfile; tarfile.open('build-ab/$p.tar.xz').extractall('/tmp/ab')"; done
n=/tmp/ab/p26; o=/tmp/ab/p23b; x=/tmp/ab/p10; w=/tmp/r3; mkdir -p $w; q=--quiet
bench() {  # bench LABEL BIN ARGS...
  local label=$1 bin=$2; shift 2
  $bin/prt-bench --backend cuda --frames 40 --warmup 5 --json $w/b.json "$@" > /dev/null 2> $w/err.txt \
    || { echo "$label failed: $(tail -2 $w/err.txt)"; return; }
  python3 - "$label" $w/b.json <<'PY'
import json, sys
j = json.load(open(sys.argv[2]))
print(sys.argv[1].ljust(28), ' '.join('%s %.3f' % (x['name'], x['grays_per_s']) for x in j['scenarios']), flush=True)
PY
}
$n/prt-bench --backend cuda --save-pool $w/room.pool --frames 1 --warmup 0 --scenarios primary $q > /dev/null 2>&1
$x/prt-cull $w/room.pool -o $w/culled.pool $q
for m in 32; do $x/prt-bricks $w/culled.pool -o $w/cb$m.pool --lod-splats $m $q; done
for r in 1 2; do for lp in 0 1; do for b in o n; do
  bench "$b bricks lod-pixels $lp" ${!b} $w/cb32.pool --scene preprocess/bench/bench_room.json --scenarios primary,shadow,full4 --lod-pixels $lp
done; done; done
echo "ALL_DONE $((SECONDS - t0)) s"
