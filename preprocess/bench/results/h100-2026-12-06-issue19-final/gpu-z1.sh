#!/usr/bin/env bash
# Issue 19, closing measurement (z1): every target of the issue with main as of 1f1a712 (the build
# packed in build-ab/kall.tar.xz), on one GPU and its host in one call: prt-bench, 1024x1024,
# median of 100 frames after 5, each scenario alone in its own process, two rounds; then the
# preprocessing chain (scripts/bench-preprocess.sh, BACKEND=auto) on 2 and 16 cores, three runs
# per step; then every GPU test program of that build, its tools beside it.
# Carried: build-ab/kall.tar.xz, build-ab/bezier.
NAME=z1 TARS=kall.tar.xz
source preprocess/bench/results/h100-2026-12-05-issue17-radii-neighbours/lib500.sh
source preprocess/bench/results/h100-2026-12-06-issue19-region-axes/alone.sh
x=$kall; q=--quiet
lscpu | grep -E "Model name|^CPU\(s\)"
# alone() (alone.sh) with 100 frames and without leaves per ray: each scenario in its own
# process, its Grays/s.
al() {
  local label=$1 scs=$2; shift 2; local line="$label"
  for sc in ${scs//,/ }; do
    $x/prt-bench --backend cuda --frames 100 --warmup 5 --json $w/b.json "$@" --scenarios $sc > /dev/null 2> $w/err.txt \
      || { line="$line $sc failed: $(tail -1 $w/err.txt)"; continue; }
    line="$line $(python3 -c "import json; s=json.load(open('$w/b.json'))['scenarios'][0]; print('%s %.3f' % (s['name'], s['grays_per_s']))")"
  done
  echo "$line"
}
make_pools $x
$x/prt-synth sphere -n 1000000 -o $w/s1.pool $q && $x/prt-radii $w/s1.pool -o $w/s1.pool --backend cuda $q \
  && $x/prt-octree $w/s1.pool -o $w/s1.pool $q && $x/prt-cull $w/s1.pool -o $w/cs1.pool $q \
  && $x/prt-iso $w/cs1.pool -o $w/is1.pool $q
$x/prt-mls $w/croom.pool -o $w/mroom.pool $q
$x/prt-patches build-ab/bezier/teapot.bpt -o $w/teapot.pool $q
echo "pools done $((SECONDS - t0)) s"
sph="--eye 0,0,3 --look-at 0,0,0 --up 0,1,0 --fov 45"; room="--scene preprocess/bench/bench_room.json"
S=primary,shadow,reflect4,full4
for r in 1 2; do
  al "r$r splats, prt-bench's room (not culled):" $S
  al "r$r splats, culled room (bench_room.json):" $S $w/croom.pool $room
  al "r$r splats, culled 1M sphere:" primary,shadow,reflect4 $w/cs1.pool $sph
  al "r$r splats, 1M sphere not culled:" primary,shadow $w/s1.pool $sph
  al "r$r splats, culled 10M sphere:" $S $w/cs10.pool $sph
  al "r$r splats, 10M sphere not culled:" primary,shadow $w/s10.pool $sph
  al "r$r ISO, culled room (bench_room.json):" $S $w/iroom.pool $room --surface iso
  al "r$r ISO, culled room (pool's view):" primary,full4 $w/iroom.pool --surface iso
  al "r$r ISO, culled 1M sphere:" primary,shadow,full4 $w/is1.pool $sph --surface iso
  al "r$r ISO, culled 10M sphere:" $S $w/is10.pool $sph --surface iso
  al "r$r MLS, culled room (pool's view):" $S $w/mroom.pool --surface mls
  al "r$r patches, teapot, --max-bounces 1:" primary,shadow,reflect4 $w/teapot.pool --max-bounces 1
done
echo "bench done $((SECONDS - t0)) s"
mkdir -p $root/build-cu && ln -sfn "$kall" $root/build-cu/bin
BACKEND=auto bash scripts/bench-preprocess.sh $root/build-cu 1000000 2,16 3
gpu_tests
echo "ALL_DONE $((SECONDS - t0)) s"
