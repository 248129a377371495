# p_hit per internal node: SA(box ∩ cell) / SA(cell) (Cauchy: chance a random line through the cell
# meets the box), box = AABB of the disks below the node (as rt::build_node_boxes), normalized coords.
import json, subprocess, sys
import numpy as np
path = sys.argv[1]
info = json.loads(subprocess.check_output([sys.argv[2], '--json', path]))
sec = {s['name']: s for s in info['sections']}
raw = open(path, 'rb').read()
def arr(name, dt):
    s = sec[name]; return np.frombuffer(raw, dtype=dt, count=s['bytes'] // np.dtype(dt).itemsize, offset=s['offset'])
oi = arr('octree_info', np.dtype([('root_min', '<f4', 3), ('root_size', '<f4'), ('rest', 'u1', 48)]))[0]
nodes = arr('octree_nodes', '<u4'); li = arr('leaf_info', '<u4')
sp = arr('splats', np.dtype([('p', '<f4', 3), ('r', '<f4'), ('n', '<f4', 3), ('pt', '<u4')]))
rm = oi['root_min'].astype(np.float64); inv = 1.0 / float(oi['root_size'])
n = sp['n'].astype(np.float64); n /= np.linalg.norm(n, axis=1)[:, None]
h = sp['r'].astype(np.float64)[:, None] * np.sqrt(np.maximum(0, 1 - n * n))
lo = (sp['p'] - h - rm) * inv; hi = (sp['p'] + h - rm) * inv
L = len(li) - 1
starts = li[:-1].astype(np.int64)
nonempty = li[1:] > li[:-1]
llo = np.full((L, 3), np.inf); lhi = np.full((L, 3), -np.inf)
idx = np.nonzero(nonempty)[0]
llo[idx] = np.minimum.reduceat(lo, starts[idx], axis=0); lhi[idx] = np.maximum.reduceat(hi, starts[idx], axis=0)
N = len(nodes); typ = nodes >> 30; adr = nodes & ((1 << 30) - 1)
blo = np.full((N, 3), np.inf); bhi = np.full((N, 3), -np.inf)
f = typ == 1; blo[f] = llo[adr[f]]; bhi[f] = lhi[adr[f]]
level = np.zeros(N, np.int64); cell = np.zeros((N, 3), np.int64)
internal = np.nonzero(typ == 0)[0]
for i in internal:  # top-down cells (children after parents)
    a = adr[i]
    for c in range(8):
        level[a + c] = level[i] + 1
        cell[a + c] = cell[i] * 2 + np.array([c & 1, (c >> 1) & 1, (c >> 2) & 1])
for i in internal[::-1]:
    a = adr[i]
    blo[i] = blo[a:a + 8].min(axis=0); bhi[i] = bhi[a:a + 8].max(axis=0)
size = 0.5 ** level[internal]
clo = cell[internal] * size[:, None]; chi = clo + size[:, None]
ilo = np.maximum(blo[internal], clo); ihi = np.minimum(bhi[internal], chi)
e = np.maximum(0, ihi - ilo)
sa = 2 * (e[:, 0] * e[:, 1] + e[:, 1] * e[:, 2] + e[:, 0] * e[:, 2])
p = sa / (6 * size * size)
print(path, 'internal nodes', len(internal))
for q in (0.25, 0.5, 0.75):
    print('  p_hit quantile %.2f: %.3f' % (q, np.quantile(p, q)))
print('  mean p_hit %.3f; nodes with p_hit < 0.5: %.1f %%; < 0.7: %.1f %%' % (p.mean(), 100 * (p < 0.5).mean(), 100 * (p < 0.7).mean()))
for l in range(1, level.max() + 1):
    m = level[internal] == l
    if m.any(): print('  level %2d: %6d nodes, mean p_hit %.3f' % (l, m.sum(), p[m].mean()))
