#!/usr/bin/env bash
# 2026-12-05 (sixth session): knn.cu's choice of the kernels' register width (8, 16 or 32 for k) in one
# dispatcher for the search and the stored clamp. The radii GPU tests of the new tree (knn2/: every
# k's width, the CPU's radii bit for bit, both ways to the clamp's neighbours), then prt-radii on the
# GPU over a 20M room with main d2ff0f4's (kall/) and the new one (knn2/): the pools' sections equal.
NAME=f4 TARS="diag.tar.xz kall.tar.xz knn2.tar.xz"
here=$(cd "$(dirname "$0")" && pwd)
. "$here/../h100-2026-12-05-issue17-radii-neighbours/lib500.sh"
timeout 300 /tmp/ab/knn2/prt_radii_gpu_tests > $out/prt_radii_gpu_tests-f4.log 2>&1
echo "knn2 prt_radii_gpu_tests rc $? $(grep -E '^\[  (PASSED|FAILED|SKIPPED)|^\[       OK' $out/prt_radii_gpu_tests-f4.log | tr '\n' ' ')"
$x/prt-synth room -n 20000000 -o $w/r20.pool --quiet
for k in 9 17; do
  for v in kall knn2; do
    /usr/bin/time -f "$v k=$k: %e s wall" /tmp/ab/$v/prt-radii $w/r20.pool -o $w/$v-$k.pool --backend cuda -k $k --quiet
    python3 $root/preprocess/bench/results/h200-2026-12-04-issue17-cells-alloc/poolsum.py $w/$v-$k.pool > $w/$v-$k.sum
  done
  cmp -s $w/kall-$k.sum $w/knn2-$k.sum && echo "radii k=$k: sections equal" || echo "radii k=$k: SECTIONS DIFFER"
done
echo "ALL_DONE $((SECONDS - t0)) s"
