import csv, gzip, sys, collections
def load(p):
    per = {}; f = None
    for r in csv.reader(gzip.open(p, 'rt')):
        if not r: continue
        if r[0] == 'File Path': f = r[1].split('/')[-1]; continue
        if r[0] and r[0].isdigit() and len(r) > 8:
            inst = int(r[7]) if r[7].isdigit() else 0
            st = int(r[4]) if r[4].isdigit() else 0
            thr = int(r[8]) if r[8].isdigit() else 0
            per[(f, int(r[0]))] = (inst, st, thr, r[1][:100])
    return per
a = load(sys.argv[1]); b = load(sys.argv[2])
ta = sum(v[0] for v in a.values()); tb = sum(v[0] for v in b.values())
print('total warp instr A %.1fM B %.1fM; stall samples A %d B %d' % (ta/1e6, tb/1e6, sum(v[1] for v in a.values()), sum(v[1] for v in b.values())))
n = int(sys.argv[3])
for k, v in sorted(b.items(), key=lambda kv: -kv[1][0])[:n]:
    va = a.get(k, (0,0,0,''))
    print('%-10s %4d B %6.2fM thr %4.1f st %5d | A %6.2fM thr %4.1f st %5d | %s' % (k[0][:10], k[1], v[0]/1e6, v[2]/max(v[0],1), v[1], va[0]/1e6, va[2]/max(va[0],1), va[1], v[3]))
