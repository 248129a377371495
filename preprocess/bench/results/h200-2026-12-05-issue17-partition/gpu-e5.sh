#!/usr/bin/env bash
# Issue 17, 2026-12-05 (fifth session): the pool reader hashing the sections at once (new5 = main
# 9efa296 + that) against main (new2): opening the 500M room's 14 GB pool alone, timed with an
# option that fails right after the input is opened and checked (--keep-float on a pool of points),
# three alternating rounds; then one whole new5 build, its sections compared with new2's.
NAME=e5 TARS="part.tar.xz"
here=$(cd "$(dirname "$0")" && pwd)
. "$here/../h100-2026-12-05-issue17-radii-neighbours/lib500.sh"
p=/tmp/ab/part; x=$p
[ -f $w/s.pool ] || synth
for r in 1 2 3; do for v in new2 new5; do
  /usr/bin/time -f "open $v: %e s wall, %U s user, %S s sys" $p/$v-bricks $w/s.pool -o $w/x.pool --keep-float --quiet 2>&1 | tail -1
done; done
line new5a $p/new5-bricks; sum new5a
line new2g $p/new2-bricks; sum new2g
compare new2g new5a
