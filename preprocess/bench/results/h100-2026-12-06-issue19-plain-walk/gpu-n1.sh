#!/usr/bin/env bash
# Issue 19, the ISO walk compiled without macro-region code (n1): prt-bench's ISO scenarios with
# --iso-walk regions, plain and auto (WalkChoice), each scenario alone in its own process, 1024x1024,
# median of 100 frames after 10, two rounds with the runtime's GPU tests of this tree between them;
# then prt-cull and prt-iso of main against this tree's (their host work on every core), 1M room.
# Carried: build-ab/tools5.tar.xz (main's prt-synth, -radii, -octree, -cull, -iso, -mls, -patches,
# -bricks: the pools, the tests' tools), this tree's prt-bench, prt_runtime_gpu_tests, prt-cull and
# prt-iso (build-ab/n1.tar.xz), build-ab/bezier.
NAME=n1 TARS="tools5.tar.xz n1.tar.xz"
source preprocess/bench/results/h100-2026-12-05-issue17-radii-neighbours/lib500.sh
source preprocess/bench/results/h100-2026-12-06-issue19-region-axes/alone.sh
x=$kall; q=--quiet; nb=/tmp/ab/n1/prt-bench
al() {  # label scenarios args...: each scenario alone, its Grays/s and leaves per ray
  local label=$1 scs=$2; shift 2; local line="$label"
  for sc in ${scs//,/ }; do
    $nb --backend cuda --frames 100 --warmup 10 --json $w/b.json "$@" --scenarios $sc > /dev/null 2> $w/err.txt \
      || { line="$line $sc failed: $(tail -1 $w/err.txt)"; continue; }
    line="$line $(python3 -c "import json; s=json.load(open('$w/b.json'))['scenarios'][0]; print('%s %.3f [%.1f l]' % (s['name'], s['grays_per_s'], s['leaves_per_ray']))")"
  done
  echo "$line"
}
cp /tmp/ab/n1/prt-bench $kall/  # make_pools saves prt-bench's room with it
make_pools $x
echo "pools done $((SECONDS - t0)) s"
sph="--eye 0,0,3 --look-at 0,0,0 --up 0,1,0 --fov 45"; room="--scene preprocess/bench/bench_room.json"
bench_round() {  # round number
  local r=$1
  for walk in regions plain auto; do
    al "r$r ISO 10M sphere, $walk:" primary,shadow,full4 $w/is10.pool $sph --surface iso --iso-walk $walk
  done
  for walk in regions plain auto; do
    al "r$r ISO culled room (bench_room.json), $walk:" primary,full4 $w/iroom.pool $room --surface iso --iso-walk $walk
  done
}
bench_round 1
echo "round 1 done $((SECONDS - t0)) s"
mkdir -p /tmp/gt; cp /tmp/ab/n1/prt_runtime_gpu_tests $kall/; mkdir -p /work/shared/data/bezier && cp -r build-ab/bezier/* /work/shared/data/bezier/
PRT_BIN_DIR=$kall timeout 300 $kall/prt_runtime_gpu_tests > $out/prt_runtime_gpu_tests-n1.log 2>&1
echo "prt_runtime_gpu_tests rc $? $(grep -E '^\[  (PASSED|FAILED|SKIPPED)' $out/prt_runtime_gpu_tests-n1.log | tr '\n' ' ')"
grep -B2 -A8 "Failure" $out/prt_runtime_gpu_tests-n1.log | head -40
bench_round 2
echo "bench done $((SECONDS - t0)) s"
# prt-cull and prt-iso of main against this tree's (leaf-chunked compaction, the octree checks on
# every core) on the chain's inputs, alternating, wall seconds, 2 rounds on 16 cores, 1 on 2.
$x/prt-cull $w/room.pool -o $w/croom-main.pool --backend cuda $q
for cores in 0-15 0-1; do
  for r in 1 2; do
    [ $cores = 0-1 ] && [ $r = 2 ] && continue
    line="cores $cores round $r:"
    for v in main tree; do
      bin=$x; [ $v = tree ] && bin=/tmp/ab/n1
      s=$(date +%s.%N); taskset -c $cores $bin/prt-cull $w/room.pool -o $w/c-$v.pool --backend cuda $q; e=$(date +%s.%N)
      s2=$(date +%s.%N); taskset -c $cores $bin/prt-iso $w/croom-main.pool -o $w/i-$v.pool $q; e2=$(date +%s.%N)
      line="$line $v cull $(python3 -c "print('%.3f iso %.3f' % ($e - $s, $e2 - $s2))")"
    done
    echo "$line"
  done
done
cmp -s <(python3 $root/preprocess/bench/results/h200-2026-12-04-issue17-cells-alloc/poolsum.py $w/c-main.pool) \
  <(python3 $root/preprocess/bench/results/h200-2026-12-04-issue17-cells-alloc/poolsum.py $w/c-tree.pool) \
  && echo "culled pools: sections equal" || echo "culled pools: SECTIONS DIFFER"
echo "ALL_DONE $((SECONDS - t0)) s"
