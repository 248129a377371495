#!/usr/bin/env bash
# Issue 19 (n2): the runtime's GPU tests of this tree (n1's call ran them without the tools beside
# them: prt-bricks not found, the surface tests skipped). Carried: as gpu-n1.sh.
NAME=n2 TARS="tools5.tar.xz n1.tar.xz"
source preprocess/bench/results/h100-2026-12-05-issue17-radii-neighbours/lib500.sh
cp /tmp/ab/n1/prt-bench /tmp/ab/n1/prt_runtime_gpu_tests $kall/
mkdir -p /work/shared/data/bezier && cp -r build-ab/bezier/* /work/shared/data/bezier/
mkdir -p $root/build-cu && ln -sfn "$kall" $root/build-cu/bin
PRT_BIN_DIR=$kall timeout 300 $kall/prt_runtime_gpu_tests > $out/prt_runtime_gpu_tests-n2.log 2>&1
echo "prt_runtime_gpu_tests rc $? $(grep -E '^\[  (PASSED|FAILED|SKIPPED)' $out/prt_runtime_gpu_tests-n2.log | tr '\n' ' ')"
grep -B2 -A8 "Failure" $out/prt_runtime_gpu_tests-n2.log | head -40
echo "ALL_DONE $((SECONDS - t0)) s"
