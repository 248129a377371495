#!/usr/bin/env bash
# Issue 17, 2026-12-05 (third session): a second round on the host that had just run gpu-d5.sh,
# still warm, reusing its 500M room (/tmp/wd5/s.pool): blocking waits at 24 and 32 cell workers
# against main. (Run as a heredoc in the call's command; saved here as it ran.)
NAME=d6 TARS="pack.tar.xz blk.tar.xz"
. "$(dirname "$0")/lib500.sh"
w=/tmp/wd5
line blk24b $blk/prt-bricks "--cell-workers 24"; sum blk24b
line main2 $x/prt-bricks; sum main2
line blk32 $blk/prt-bricks "--cell-workers 32"; sum blk32
compare main2 blk24b blk32
