#!/usr/bin/env bash
# A/B of prt-bricks from points on a 100M room: old = CUDA culling on the legacy default stream,
# new = each culling call on its own stream, stream-ordered allocations, blocking waits.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"; exec > >(tee "$out/s5.txt") 2>&1
bin=$PWD/build-cuda/bin; w=/tmp/ws; mkdir -p $w
cp build-cuda/pack/prt-bricks-old $w/
T='%e s wall, %U user, %S sys'
[ -f $w/s100.pool ] || { $bin/prt-synth room -n 100000000 -o $w/s100.pool --quiet; echo "synth 100M rc $?"; }
for r in 1 2; do
  for who in old new; do
    b=$bin/prt-bricks; [ $who = old ] && b=$w/prt-bricks-old
    /usr/bin/time -f "r$r $who: $T" $b $w/s100.pool -o $w/b-$who.pool --memory 12G 2> $w/b.err; echo "r$r $who rc $?"
    grep -E "s partitioning|building \(|wall," $w/b.err
  done
done
echo "pools: $(stat -c %s $w/b-old.pool) $(stat -c %s $w/b-new.pool) bytes; differing bytes: $(cmp -l $w/b-old.pool $w/b-new.pool | wc -l)"; cmp -l $w/b-old.pool $w/b-new.pool | head -3
echo ALL_DONE
