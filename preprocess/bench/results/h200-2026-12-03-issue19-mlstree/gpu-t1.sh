#!/usr/bin/env bash
# Issue 19, MLS on the GPU (H200): which kd-tree the GPU walk wants. The culled 1M room and the
# 1M sphere, trees built with prt-mls's options (WS05 3.4.1 slices, 3.4.2 encouraged splits, the
# SAH's traversal cost), traced with 1 and 2 regula falsi steps (cd84556's binaries, pack7).
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/t1.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; t0=$SECONDS
rm -rf /tmp/ab; mkdir -p /tmp/ab
python3 -c "import tarfile; tarfile.open('build-ab/pack7.tar.xz').extractall('/tmp/ab')"
x=/tmp/ab/p7; w=/tmp/t1; rm -rf $w; mkdir -p $w; q=--quiet
$x/prt-bench --save-pool $w/room.pool --frames 1 --warmup 0 --scenarios primary --backend cuda $q > /dev/null
$x/prt-cull $w/room.pool -o $w/culled.pool $q
$x/prt-synth sphere -n 1000000 -o $w/sphere.pool $q && $x/prt-radii $w/sphere.pool -o $w/sphere.pool $q
V=("def:" "noenc:--no-encourage" "ne_sl16:--no-encourage --slices 16" "ne_sl32:--no-encourage --slices 32"
   "ne_ct5:--no-encourage --cost-traversal 5" "ne_sl16ct5:--no-encourage --slices 16 --cost-traversal 5"
   "ne_sl32ct3:--no-encourage --slices 32 --cost-traversal 3")
for v in "${V[@]}"; do n=${v%%:*}; a=${v#*:}
  s=$SECONDS; $x/prt-mls $w/culled.pool -o $w/room-$n.pool $q $a; r=$((SECONDS - s))
  s=$SECONDS; $x/prt-mls $w/sphere.pool -o $w/sphere-$n.pool $q $a; echo "built $n: room ${r} s, sphere $((SECONDS - s)) s"
done
bench() {  # bench LABEL POOL ARGS...
  local label=$1 pool=$2; shift 2
  $x/prt-bench --backend cuda --frames 20 --warmup 3 --surface mls --json $w/b.json $pool "$@" > /dev/null 2> $w/err.txt \
    || { echo "$label failed: $(tail -2 $w/err.txt)"; return; }
  python3 - "$label" $w/b.json <<'PY'
import json, sys
j = json.load(open(sys.argv[2]))
print(sys.argv[1].ljust(24), ' '.join('%s %.4f' % (x['name'], x['grays_per_s']) for x in j['scenarios']), flush=True)
PY
}
S=primary,shadow,reflect4,full4; SPH="--eye 0,0,3 --look-at 0,0,0 --up 0,1,0 --fov 45"
for round in 1 2; do
  for v in "${V[@]}"; do n=${v%%:*}
    for r in 1 2; do
      [ $n = def ] || [ $r = 2 ] || [ $n = noenc ] || continue
      bench "room $n r$r" $w/room-$n.pool --scenarios $S --mls-refine $r
      bench "sphere $n r$r" $w/sphere-$n.pool --scenarios primary,shadow $SPH --mls-refine $r
    done
  done
done
echo "ALL_DONE $((SECONDS - t0)) s"
