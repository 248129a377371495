#!/bin/bash
# Bisecting the 1M room's primary-ray regression (1.06 Grays/s at 164496a, 0.78 at the working
# tree, same H200): prt-bench built from each commit archived in .device-deps/old (git archive),
# all built side by side, then run one after the other (primary, shadow, reflect4). Writes $OUT.
set -uo pipefail
OUT=${OUT:-/tmp/out}
mkdir -p "$OUT"
exec > >(tee "$OUT/bisect.txt") 2>&1
F="-DCMAKE_PREFIX_PATH=$PWD/.device-deps/usr -DPRT_WITH_PCL=OFF -DPRT_WITH_OPENMESH=OFF -DPRT_WITH_OIIO=OFF -DPRT_WITH_PYTHON=OFF -DPRT_WITH_GLFW=OFF -DCMAKE_BUILD_TYPE=Release"
versions="$*"
t0=$(date +%s)
for v in $versions; do
    ( [ -x /tmp/v-$v/build/bin/prt-bench ] || { mkdir -p /tmp/v-$v && tar -xzf .device-deps/old/$v.tar.gz -C /tmp/v-$v &&
      cmake -S /tmp/v-$v -B /tmp/v-$v/build $F >/tmp/v-$v.cmake.txt 2>&1 &&
      cmake --build /tmp/v-$v/build -j3 --target prt-bench >/tmp/v-$v.build.txt 2>&1 || tail -5 /tmp/v-$v.build.txt; } ) &
done
wait
echo "built in $(( $(date +%s) - t0 )) s"
for v in $versions; do
    rm -f /tmp/r.json
    /tmp/v-$v/build/bin/prt-bench --scenarios primary,shadow,reflect4 -q --json /tmp/r.json >/dev/null 2>&1
    python3 -c "
import json; d = json.load(open('/tmp/r.json'))
print('$v', [(s.get('name', s.get('scenario')), round(s['grays_per_s'], 3), round(s.get('leaves_per_ray', 0), 2), round(s.get('splat_tests_per_ray', 0), 2)) for s in d['scenarios']])" || echo "$v: no result"
done
