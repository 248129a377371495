#!/usr/bin/env bash
# Issue 17, 2026-12-05 (third session): what landing radii-stored-neighbours.patch needs, in one call.
# kall/ is main db13c1e with the patch, every tool and GPU test program (build-ab/kall.tar.xz);
# bin/ is main db13c1e's prt-bricks and prt-synth; blk/ is db13c1e + blocking-waits.patch. Every
# GPU test program of kall/, then the 500M room from points (--memory 12G, 16 cores): main, the
# patch, and, while the call's time allows, blocking waits at 24 cell workers; sections compared.
NAME=d5 TARS="pack.tar.xz kall.tar.xz blk.tar.xz"
. "$(dirname "$0")/lib500.sh"
gpu_tests
synth
line main1 $x/prt-bricks; sum main1
line knn1 $kall/prt-bricks; sum knn1
if (( SECONDS - t0 < 420 )); then line blk24 $blk/prt-bricks "--cell-workers 24"; sum blk24; compare main1 knn1 blk24
else compare main1 knn1; fi
