#!/usr/bin/env bash
# Issue 17, pending (written 2026-12-05, no device lent): the local clamp's neighbours stored by the
# GPU's k-NN search instead of found by a second search (radii-stored-neighbours.patch). Carried:
# build-ab/pack.tar.xz (main's binaries and GPU tests, folder bin/) and build-ab/knn.tar.xz (folder
# knn/: prt-bricks, prt-radii and prt_radii_gpu_tests built with the patch applied to the same main).
# 1. the patched radii GPU tests (the CPU's radii bit for bit, both ways to the neighbours equal);
# 2. the 500M room from points (prt-synth's pool straight into prt-bricks, --memory 12G, 16 cores),
#    main / knn / main / knn, each pool's sections summarised and compared, the pools removed as it goes.
NAME=d1 TARS="pack.tar.xz knn.tar.xz"
. "$(dirname "$0")/lib500.sh"
radii_tests
synth
line main1 $x/prt-bricks; sum main1
line knn1 $knn/prt-bricks; sum knn1
line main2 $x/prt-bricks; sum main2
line knn2 $knn/prt-bricks; sum knn2
compare main1 knn1 main2 knn2
