#!/usr/bin/env bash
# Issue 17, pending (written 2026-12-05, no device lent): cell workers that sleep while they wait for
# the GPU (blocking-waits.patch: cudaDeviceScheduleBlockingSync when prt-bricks builds cells on the
# GPU with several workers), so that more workers than cores can fill the cores with the cells' CPU
# work. Carried: build-ab/pack.tar.xz (main, folder bin/) and build-ab/blk.tar.xz (folder blk/:
# prt-bricks built with the patch applied to the same main). The 500M room from points
# (--memory 12G, 16 cores): main, blk, blk with 24 and 32 cell workers, and main with glibc's malloc
# keeping freed blocks below 32 MiB in its arenas (tun16: does the cells' allocation churn, fresh
# zeroed pages for every cell, cost the host's 57 s of system time?); sections compared, pools
# removed as it goes.
NAME=d2 TARS="pack.tar.xz blk.tar.xz"
. "$(dirname "$0")/lib500.sh"
synth
line main1 $x/prt-bricks; sum main1
line blk16 $blk/prt-bricks; sum blk16
line blk24 $blk/prt-bricks "--cell-workers 24"; sum blk24
line blk32 $blk/prt-bricks "--cell-workers 32"; sum blk32
export GLIBC_TUNABLES=glibc.malloc.mmap_threshold=33554432:glibc.malloc.trim_threshold=4294967296
line tun16 $x/prt-bricks; unset GLIBC_TUNABLES; sum tun16
compare main1 blk16 blk24 blk32 tun16
