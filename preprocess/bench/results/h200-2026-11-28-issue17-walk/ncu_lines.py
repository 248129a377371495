#!/usr/bin/env python3
"""Per-file and per-line warp instructions and stall samples of two ncu source pages
(`ncu -i REP --page source --csv --print-source cuda,sass | gzip`): ncu_lines.py A.csv.gz B.csv.gz [N]
prints the files, then B's N busiest lines with A's count beside them. Used for w2 (float against
bricks, room primary) and w4 (variant B against A, room shadow)."""
import csv, gzip, sys, collections
def load(p):
    per_line = {}; per_file = collections.Counter(); stall = collections.Counter()
    f = None; src = None
    for r in csv.reader(gzip.open(p, 'rt')):
        if not r: continue
        if r[0] == 'File Path': f = r[1].split('/')[-1]; continue
        if r[0] in ('Function Name', 'Line No'): continue
        if r[0] and r[0].isdigit():
            inst = int(r[7]) if r[7].isdigit() else 0
            st = int(r[4]) if r[4].isdigit() else 0
            per_line[(f, int(r[0]))] = (inst, st, r[1][:90], r[8])
            per_file[f] += inst; stall[f] += st
    return per_line, per_file, stall
a = load(sys.argv[1]); b = load(sys.argv[2])
print('per file: warp instructions (M) and stall samples, A then B')
for f in sorted(set(a[1]) | set(b[1]), key=lambda f: -(b[1][f])):
    print('%-28s %8.1f %8.1f   %8d %8d' % (f, a[1][f] / 1e6, b[1][f] / 1e6, a[2][f], b[2][f]))
print('total', sum(a[1].values()) / 1e6, sum(b[1].values()) / 1e6)
n = int(sys.argv[3]) if len(sys.argv) > 3 else 60
print('\nB\'s top lines by warp instructions (A\'s beside them)')
for k, v in sorted(b[0].items(), key=lambda kv: -kv[1][0])[:n]:
    fa = a[0].get(k, (0,))[0]
    print('%-16s %5d %7.2fM (A %6.2fM) thr/warp %5.1f stall %6d  %s' % (k[0][:16], k[1], v[0] / 1e6, fa / 1e6, (int(v[3]) / v[0]) if v[0] and v[3].isdigit() else 0, v[1], v[2]))
