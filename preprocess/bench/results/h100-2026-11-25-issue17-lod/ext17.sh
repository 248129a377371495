bin=$PWD/build-dev/bin; w=/tmp/w17j; [ -f $w/b.pool ] || { echo "NO POOL (fresh machine)"; exit 3; }
pool=$(stat -c %s $w/b.pool); budget=$(( pool / 8 ))
cam="--eye 0.3,0.9,3.2 --look-at 0,-0.2,0 --up 0,1,0 --fov 50 --width 1024 --height 1024"
for lod in 1 0; do
  echo "== exterior view, --lod-pixels $lod"
  s0=$(date +%s.%N); $bin/prt-play $w/b.pool --backend cuda --gpu-budget $budget --lod-pixels $lod $cam --converge --out $w/xc$lod.pfm 2>$w/xc$lod.err; echo "converge run: $(python3 -c "import time;print(round(time.time()-$s0,2))") s wall"; grep -E "pass|converge" $w/xc$lod.err | tail -3
  $bin/prt-play $w/b.pool --backend cuda --lod-pixels $lod $cam --out $w/xi$lod.pfm --quiet
  $bin/prt-bench --backend cuda $w/b.pool --gpu-budget $budget --lod-pixels $lod $cam --frames 30 --warmup 5 2>&1 | grep -E "^primary|^shadow" | head -2
  $bin/prt-bench --backend cuda $w/b.pool --lod-pixels $lod $cam --frames 30 --warmup 5 2>&1 | grep -E "^primary|^shadow" | head -2
  $bin/prt-play $w/b.pool --backend cuda --gpu-budget $budget --lod-pixels $lod $cam --frames 100 --orbit 3.6 --converge --out $w/xo$lod.pfm 2>$w/xo$lod.err
done
python3 - $w $OUT <<'PY'
import re, sys, numpy as np, zlib, struct
d, o = sys.argv[1], sys.argv[2]
def pfm(p):
    with open(p, 'rb') as f:
        kind = f.readline().strip(); w, h = map(int, f.readline().split()); s = float(f.readline())
        return np.frombuffer(f.read(), dtype='<f4' if s < 0 else '>f4').reshape(h, w, 3)
def png(a, path):
    a = (np.clip(a[::-1], 0, 1) ** (1 / 2.2) * 255 + 0.5).astype(np.uint8)
    raw = b''.join(b'\x00' + r.tobytes() for r in a)
    ch = lambda t, x: struct.pack('>I', len(x)) + t + x + struct.pack('>I', zlib.crc32(t + x) & 0xffffffff)
    open(path, 'wb').write(b'\x89PNG\r\n\x1a\n' + ch(b'IHDR', struct.pack('>IIBBBBB', a.shape[1], a.shape[0], 8, 2, 0, 0, 0)) + ch(b'IDAT', zlib.compress(raw, 6)) + ch(b'IEND', b''))
for lod in '10':
    a, b = pfm(f'{d}/xc{lod}.pfm'), pfm(f'{d}/xi{lod}.pfm')
    print('lod %s converged vs in-core: %d pixels differ' % (lod, int((np.abs(a - b).max(axis=2) > 0).sum())))
a, b = pfm(f'{d}/xi1.pfm'), pfm(f'{d}/xi0.pfm')
diff = np.abs(a - b).max(axis=2)
print('in-core lod1 vs lod0: %d pixels differ > 0, %d > 4/255, mean abs %.4f, PSNR %.2f dB' % (int((diff > 0).sum()), int((diff > 4/255).sum()), float(np.abs(a-b).mean()), 10*np.log10(1/np.mean((np.clip(a,0,1)-np.clip(b,0,1))**2))))
png(a, f'{o}/ext_lod1.png'); png(b, f'{o}/ext_lod0.png')
png(pfm(f'{d}/incore1.pfm'), f'{o}/room_incore.png')
for lod in '10':
    ms = []; frames = {}
    for line in open(f'{d}/xo{lod}.err'):
        m = re.search(r'frame (\d+)( pass \d+)?: ([\d.]+) ms', line)
        if m: ms.append(float(m.group(3))); frames[int(m.group(1))] = frames.get(int(m.group(1)), 0) + float(m.group(3))
    nc = sum(1 for l in open(f'{d}/xo{lod}.err') if 'does not converge' in l)
    if ms:
        f = np.array(list(frames.values()))
        print('lod %s exterior orbit --converge: %d passes, %d frames not converging; per frame median %.2f, p95 %.2f, max %.2f ms, > 50 ms: %d' % (lod, len(ms), nc, np.median(f), np.percentile(f, 95), f.max(), int((f > 50).sum())))
PY
