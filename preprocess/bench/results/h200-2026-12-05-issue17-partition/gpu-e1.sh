#!/usr/bin/env bash
# Issue 17, 2026-12-05 (fifth session): the partition passes of the 500M room from points
# (--memory 12G, 16 cores). part/ holds prt-bricks of main 6242e80 (old), main + the count pass's
# centre placement (new), and that + the records written to parts of whole cells, a spill file
# each (new2), with main's prt-synth. Alternating rounds while the call's time allows; the pools'
# sections compared.
NAME=e1 TARS="part.tar.xz"
. "$(dirname "$0")/../h100-2026-12-05-issue17-radii-neighbours/lib500.sh"
p=/tmp/ab/part; x=$p
nproc; grep -m1 "model name" /proc/cpuinfo; uname -r; df -h /tmp | tail -1
synth
line old1 $p/old-bricks; sum old1
line new2a $p/new2-bricks; sum new2a
line new1 $p/new-bricks; sum new1
if (( SECONDS - t0 < 430 )); then line new2b $p/new2-bricks; sum new2b; compare old1 new2a new1 new2b
else compare old1 new2a new1; fi
