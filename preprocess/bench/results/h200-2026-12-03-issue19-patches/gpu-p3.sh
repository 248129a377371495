#!/usr/bin/env bash
# Issue 19, patches (H200): the apex solve on projected cubics (pack15) against before (pack14),
# both with the per-item debug dump; teapot, two alternating rounds, then the new tail.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/p3.txt") 2>&1
t0=$SECONDS; rm -rf /tmp/ab; mkdir -p /tmp/ab
for p in pack10 pack14 pack15; do python3 -c "import tarfile; tarfile.open('build-ab/$p.tar.xz').extractall('/tmp/ab')"; done
x=/tmp/ab/p10; w=/tmp/p3; mkdir -p $w; q=--quiet
$x/prt-patches build-ab/teapot.bpt -o $w/teapot.pool $q
cat > $w/tail.py <<'PY'
import numpy as np, sys
a = np.fromfile(sys.argv[1], dtype=np.uint64).reshape(-1, 3)[:32768]
cyc = a[:, 0].astype(np.float64); g0 = a[:, 1].astype(np.int64); dur = (a[:, 2] & ((1 << 48) - 1)).astype(np.int64); sm = (a[:, 2] >> 48).astype(np.int64)
t0 = g0.min(); end = g0 + dur
fin = np.array([end[sm == s].max() - t0 for s in range(132) if (sm == s).any()])
print('  span %.1f us; item cycles mean %.0f median %.0f p99 %.0f max %.0f; SM finish min %.1f median %.1f max %.1f us' % ((end.max() - t0) / 1e3, cyc.mean(), np.median(cyc), np.percentile(cyc, 99), cyc.max(), fin.min() / 1e3, np.median(fin) / 1e3, fin.max() / 1e3))
for i in np.argsort(-cyc)[:int(sys.argv[2])]:
    tile = i // 8
    print('  item %5d tile (%2d,%2d) sub %d: %8.0f cycles start %6.1f us' % (i, tile % 64, tile // 64, i % 8, cyc[i], (g0[i] - t0) / 1e3))
PY
for r in 1 2; do for v in p14 p15; do
  for s in primary shadow reflect4; do
    PRT_ITEM_DUMP=$w/i.bin /tmp/ab/$v/prt-bench --backend cuda --frames 20 --warmup 3 --max-bounces 1 --scenarios $s $w/teapot.pool $q | grep -E "^$s" | awk -v v=$v '{print v, $1, $2, "ms", $8, "Grays/s"}'
    python3 $w/tail.py $w/i.bin $([ $r = 2 ] && echo 8 || echo 0)
  done
done; done
for v in p14 p15; do /tmp/ab/$v/prt-bench --backend cuda --frames 10 --warmup 3 --max-bounces 1 --scenarios primary,reflect4 --width 2048 --height 2048 $w/teapot.pool $q | grep -E "^(primary|reflect4)" | awk -v v=$v '{print v, "2048", $1, $2, "ms", $8, "Grays/s"}'; done
echo "ALL_DONE $((SECONDS - t0)) s"
