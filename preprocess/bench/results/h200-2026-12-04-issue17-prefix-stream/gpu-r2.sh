#!/usr/bin/env bash
# Issue 17 (H200): streamed LOD prefixes, second run: prt-play --converge now stops a still view
# whose passes bring no fewer fallbacks in 32 passes (rt::Refinement; r1's --lod-splats 32 inside
# view re-uploaded prefixes for 120 s). The 100M room, --lod-splats 32 and 12, under pool/8: the
# inside view, the 100-frame orbit; the outside view under pool/4 and pool/2; in-core speed of
# both pools and of prt-bench's bricked culled 1M room (bench_room.json) at --lod-splats 32 and 12.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/r2.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; t0=$SECONDS
rm -rf /tmp/ab; mkdir -p /tmp/ab
for p in pack10 pack26; do python3 -c "import tarfile; tarfile.open('build-ab/$p.tar.xz').extractall('/tmp/ab')"; done
n=/tmp/ab/p26; x=/tmp/ab/p10; w=/tmp/r2; mkdir -p $w; q=--quiet
s=$SECONDS; $x/prt-synth room -n 100000000 -o $w/s.pool $q; echo "synth 100M: rc $? $((SECONDS - s)) s"
for m in 32 12; do $x/prt-bricks $w/s.pool -o $w/b$m.pool --memory 12G --lod-splats $m $q; done; rm -f $w/s.pool
pool=$(stat -c %s $w/b32.pool); echo "pools $pool / $(stat -c %s $w/b12.pool) B"
inside="--eye 0.55,0.1,0.75 --look-at 0,-0.4,0 --up 0,1,0 --fov 60 --width 1024 --height 1024"
outside="--eye 0.3,0.9,3.2 --look-at 0,-0.2,0 --up 0,1,0 --fov 50 --width 1024 --height 1024"
conv() {  # conv M VIEW DIVISOR
  local cam=${!2} budget=$(( pool / $3 ))
  s=$(date +%s.%N); timeout 100 $n/prt-play $w/b$1.pool --backend cuda --gpu-budget $budget $cam --converge --out $w/conv.ppm 2> $w/conv-$1-$2-$3.err
  echo "M=$1 $2 pool/$3: rc $? $(python3 -c "print(round($(date +%s.%N) - $s, 2))") s wall; $(grep -E 'converge|pass\(es\)' $w/conv-$1-$2-$3.err | tail -2 | tr '\n' ' ' | cut -c1-260)"
  grep -E "pass [0-9]+:" $w/conv-$1-$2-$3.err | tail -1 | cut -c1-330
}
for m in 32 12; do conv $m inside 8; done
for d in 4 2; do for m in 32 12; do conv $m outside $d; done; done
for m in 32 12; do
  timeout 200 $n/prt-play $w/b$m.pool --backend cuda --gpu-budget $(( pool / 8 )) $inside --frames 100 --orbit 3.6 --converge --out $w/orbit.ppm 2> $w/orbit-$m.err
  echo "M=$m inside orbit, 3.6 degrees a frame, --converge: rc $?"; python3 preprocess/bench/results/h200-2026-11-29-issue17-light/orbit_summary.py $w/orbit-$m.err
done
bench() {  # bench LABEL ARGS...
  local label=$1; shift
  $n/prt-bench --backend cuda --frames 30 --warmup 5 --json $w/b.json "$@" > /dev/null 2> $w/err.txt \
    || { echo "$label failed: $(tail -2 $w/err.txt)"; return; }
  python3 - "$label" $w/b.json <<'PY'
import json, sys
j = json.load(open(sys.argv[2]))
print(sys.argv[1].ljust(28), ' '.join('%s %.3f' % (x['name'], x['grays_per_s']) for x in j['scenarios']), flush=True)
PY
}
for m in 32 12; do bench "100M room M=$m inside" $w/b$m.pool $inside --scenarios primary,shadow; done
$n/prt-bench --backend cuda --save-pool $w/room.pool --frames 1 --warmup 0 --scenarios primary $q > /dev/null 2>&1
$x/prt-cull $w/room.pool -o $w/culled.pool $q
for m in 32 12; do $x/prt-bricks $w/culled.pool -o $w/cb$m.pool --lod-splats $m $q; done
for r in 1 2; do
  bench "culled room float" $w/culled.pool --scene preprocess/bench/bench_room.json --scenarios primary,shadow,full4
  for m in 32 12; do bench "culled room bricks M=$m" $w/cb$m.pool --scene preprocess/bench/bench_room.json --scenarios primary,shadow,full4; done
done
tar -czf $out/errs.tar.gz -C $w $(cd $w && ls *.err)
echo "ALL_DONE $((SECONDS - t0)) s"
