#!/usr/bin/env bash
# Issue 19, MLS on the GPU (H200), fourth call: each cell sampled over the span where the ray meets
# its supports (clip, pack4) against 884bfa6 (new, pack2); images of both, Nsight Compute on clip's
# primary frame and the GPU tests.
# build-ab/pack2.tar.xz: the tools and new; pack4.tar.xz: clip.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/m4.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; t0=$SECONDS
rm -rf /tmp/ab; mkdir -p /tmp/ab
python3 -c "import tarfile; [tarfile.open('build-ab/pack%d.tar.xz' % i).extractall('/tmp/ab') for i in (2, 4)]"
b=/tmp/ab/p2; n=/tmp/ab/p2; x=/tmp/ab/p4; w=/tmp/m4; rm -rf $w; mkdir -p $w; q=--quiet
$b/prt-bench --save-pool $w/room.pool --frames 1 --warmup 0 --scenarios primary --backend cuda $q > /dev/null
$b/prt-cull $w/room.pool -o $w/culled.pool $q && $b/prt-iso $w/culled.pool -o $w/surf.pool $q
$b/prt-mls $w/surf.pool -o $w/mls.pool $q
$b/prt-mls $w/surf.pool -o $w/mls-noenc.pool --no-encourage $q
$b/prt-synth sphere -n 1000000 -o $w/sphere.pool $q && $b/prt-radii $w/sphere.pool -o $w/sphere.pool $q \
  && $b/prt-mls $w/sphere.pool -o $w/sphere.pool $q
echo "pools $((SECONDS - t0)) s"
bench() {  # bench LABEL BIN ARGS...
  local label=$1 bin=$2; shift 2
  $bin/prt-bench --backend cuda --frames 20 --warmup 3 --surface mls --json $w/b.json "$@" > /dev/null 2> $w/err.txt \
    || { echo "$label failed: $(tail -2 $w/err.txt)"; return; }
  python3 - "$label" $w/b.json <<'PY'
import json, sys
j = json.load(open(sys.argv[2]))
print(sys.argv[1].ljust(22), ' '.join('%s %.4f' % (x['name'], x['grays_per_s']) for x in j['scenarios']), flush=True)
PY
}
S=primary,shadow,reflect4,full4
SPH="--eye 0,0,3 --look-at 0,0,0 --up 0,1,0 --fov 45"
for r in 1 2; do
  bench "room new" $n $w/mls.pool --scenarios $S
  bench "room clip" $x $w/mls.pool --scenarios $S
  bench "room-noenc new" $n $w/mls-noenc.pool --scenarios $S
  bench "room-noenc clip" $x $w/mls-noenc.pool --scenarios $S
  bench "sphere new" $n $w/sphere.pool --scenarios $S $SPH
  bench "sphere clip" $x $w/sphere.pool --scenarios $S $SPH
done
echo "bench $((SECONDS - t0)) s"
for pl in mls mls-noenc sphere; do  # the same image from both walks (float PFM, byte for byte)
  cam=""; [ $pl = sphere ] && cam="$SPH"
  for y in n x; do eval bin=\$$y; $bin/prt-play $w/$pl.pool --surface mls --backend cuda --out $w/$pl-$y.pfm --quiet $cam > /dev/null 2>&1 || echo "prt-play $pl $y failed"; done
  cmp $w/$pl-n.pfm $w/$pl-x.pfm && echo "image $pl: new and clip byte-identical"
done
for y in n x; do eval bin=\$$y; $bin/prt-play $w/mls.pool --surface mls --backend cuda --out $out/room-mls-$y.ppm --quiet > /dev/null 2>&1; done
python3 - $w <<'PY'
import sys, struct
w = sys.argv[1]
def pfm(p):
    d = open(p, 'rb').read(); hdr = d.split(b'\n', 3); wd, ht = map(int, hdr[1].split())
    return wd, ht, struct.unpack('<%df' % (wd * ht * 3), d[len(b'\n'.join(hdr[:3])) + 1:][:wd * ht * 12])
for pl in ('mls', 'mls-noenc', 'sphere'):
    wd, ht, a = pfm('%s/%s-n.pfm' % (w, pl)); _, _, b = pfm('%s/%s-x.pfm' % (w, pl))
    diff = sum(1 for i in range(wd * ht) if a[3 * i:3 * i + 3] != b[3 * i:3 * i + 3])
    print('image %s: %d of %d pixels differ between new and clip' % (pl, diff, wd * ht), flush=True)
PY
NCU=/usr/local/cuda/bin/ncu
$NCU --section SourceCounters --section LaunchStats --section Occupancy --section WarpStateStats --section SpeedOfLight --import-source yes -k regex:'render' --launch-skip 2 --launch-count 1 -f -o /tmp/src-clip $x/prt-bench --backend cuda $w/mls.pool --surface mls --scenarios primary --frames 1 --warmup 2 -q > /tmp/ncu-new.log 2>&1
echo "ncu rc $? $((SECONDS - t0)) s"
$NCU -i /tmp/src-clip.ncu-rep --page source --csv --print-source cuda,sass 2>/dev/null | gzip -c > $out/sass-clip.csv.gz
$NCU -i /tmp/src-clip.ncu-rep --page details 2>/dev/null | grep -E "Duration|Registers Per|Achieved Occupancy|Warp Cycles Per Issued|Avg. Active Threads|Compute \(SM\) Throughput|Issued Ipc" | head -20
[ -f build-ab/ncu_lines.py ] && python3 build-ab/ncu_lines.py $out/sass-clip.csv.gz $out/sass-clip.csv.gz 40 > $out/lines-clip.txt 2>&1
mkdir -p /work/main/build-cu && ln -sfn "$x" /work/main/build-cu/bin
for t in prt_mls_gpu_tests prt_runtime_gpu_tests prt_iso_gpu_tests prt_stability_gpu_tests; do
  PRT_BIN_DIR=$x $x/$t > $out/$t.log 2>&1; echo "$t rc $? $(grep -E '^\[  (PASSED|FAILED|SKIPPED)' $out/$t.log | tr '\n' ' ')"
done
echo "ALL_DONE $((SECONDS - t0)) s"
