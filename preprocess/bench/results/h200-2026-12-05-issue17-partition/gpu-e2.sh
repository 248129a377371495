#!/usr/bin/env bash
# Issue 17, 2026-12-05 (fifth session): a second round on the host that had just run gpu-e1.sh,
# still warm, reusing its 500M room (/tmp/we1/s.pool): main (old) and the records in parts (new2)
# alternating, to see the passes' spread.
NAME=e2 TARS="part.tar.xz"
. "$(dirname "$0")/../h100-2026-12-05-issue17-radii-neighbours/lib500.sh"
p=/tmp/ab/part; w=/tmp/we1
ls -la $w
line new2c $p/new2-bricks; sum new2c
line old2 $p/old-bricks; sum old2
line new2d $p/new2-bricks; sum new2d
if (( SECONDS - t0 < 450 )); then line old3 $p/old-bricks; sum old3; compare old2 new2c new2d old3
else compare old2 new2c new2d; fi
