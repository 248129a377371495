#!/usr/bin/env bash
# Issue 17, 2026-12-05: gpu-d1.sh and gpu-d2.sh in one call (devices were scarce that day): the
# patched radii GPU tests, then the 500M room from points (--memory 12G, 16 cores) with main
# (c10383a, bin/), knn (48ab991 + radii-stored-neighbours.patch, knn/), and blk
# (c10383a + blocking-waits.patch, blk/) at 24 and 32 cell workers; sections compared.
NAME=d3 TARS="pack.tar.xz knn.tar.xz blk.tar.xz"
. "$(dirname "$0")/lib500.sh"
radii_tests
synth
line main1 $x/prt-bricks; sum main1
line knn1 $knn/prt-bricks; sum knn1
line blk24 $blk/prt-bricks "--cell-workers 24"; sum blk24
line blk32 $blk/prt-bricks "--cell-workers 32"; sum blk32
compare main1 knn1 blk24 blk32
