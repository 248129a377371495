#!/usr/bin/env bash
# Issue 17, 2026-12-05: gpu-d3.sh cut to what a small device budget holds: the patched radii GPU
# tests, then the 500M room from points (--memory 12G, 16 cores) with main (c10383a, bin/) and knn
# (48ab991 + radii-stored-neighbours.patch, knn/), one run each; sections compared.
NAME=d4 TARS="pack.tar.xz knn.tar.xz"
. "$(dirname "$0")/lib500.sh"
radii_tests
synth
line main1 $x/prt-bricks; sum main1
line knn1 $knn/prt-bricks; sum knn1
compare main1 knn1
