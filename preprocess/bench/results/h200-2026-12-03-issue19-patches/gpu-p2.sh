#!/usr/bin/env bash
# Issue 19, patches (H200): per-item cycles and SM finish times of the teapot's primary frame
# (pack14: prt-bench with a debug dump of each 32-pixel item's clock64 / globaltimer).
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/p2.txt") 2>&1
t0=$SECONDS; rm -rf /tmp/ab; mkdir -p /tmp/ab
for p in pack10 pack14; do python3 -c "import tarfile; tarfile.open('build-ab/$p.tar.xz').extractall('/tmp/ab')"; done
x=/tmp/ab/p10; y=/tmp/ab/p14; w=/tmp/p2; mkdir -p $w; q=--quiet
$x/prt-patches build-ab/teapot.bpt -o $w/teapot.pool $q
for s in primary reflect4; do
  PRT_ITEM_DUMP=$w/items-$s.bin $y/prt-bench --backend cuda --frames 5 --warmup 3 --max-bounces 1 --scenarios $s $w/teapot.pool $q | grep -E "^$s"
  cp $w/items-$s.bin $out/
  python3 - $w/items-$s.bin <<'PY'
import numpy as np, sys
a = np.fromfile(sys.argv[1], dtype=np.uint64).reshape(-1, 3)
n = 32768; a = a[:n]
cyc = a[:, 0].astype(np.float64); g0 = a[:, 1].astype(np.int64); dur = (a[:, 2] & ((1 << 48) - 1)).astype(np.int64); sm = (a[:, 2] >> 48).astype(np.int64)
t0 = g0.min(); end = g0 + dur
print('frame span %.1f us (globaltimer), items %d' % ((end.max() - t0) / 1e3, n))
print('item cycles: mean %.0f median %.0f p99 %.0f p999 %.0f max %.0f sum/132 %.0f' % (cyc.mean(), np.median(cyc), np.percentile(cyc, 99), np.percentile(cyc, 99.9), cyc.max(), cyc.sum() / 132))
print('item ns: mean %.0f max %.0f' % (dur.mean(), dur.max()))
fin = np.array([end[sm == s].max() - t0 for s in range(132) if (sm == s).any()])
print('SM finish (us): min %.1f median %.1f max %.1f' % (fin.min() / 1e3, np.median(fin) / 1e3, fin.max() / 1e3))
order = np.argsort(-cyc)[:25]
for i in order:
    tile = i // 8; tx = tile % 64; ty = tile // 64
    print('item %5d tile (%2d,%2d) sub %d: %8.0f cycles, %7.1f us, start %7.1f us, sm %d' % (i, tx, ty, i % 8, cyc[i], dur[i] / 1e3, (g0[i] - t0) / 1e3, sm[i]))
late = np.argsort(-(end))[:10]
print('last items to finish:', [(int(i), round((g0[i]-t0)/1e3,1), round(dur[i]/1e3,1)) for i in late])
PY
done
echo "ALL_DONE $((SECONDS - t0)) s"
