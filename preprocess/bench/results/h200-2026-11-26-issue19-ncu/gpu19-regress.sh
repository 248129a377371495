#!/bin/bash
# Is the 1M room's primary rate (0.78 Grays/s on this H200 today, 1.12 on 2026-11-22's H200) a
# regression of the code? The same prt-bench run built from 164496a (2026-11-22), 964ab50
# (2026-11-24) and the working tree, one after the other on one machine. Source archives in
# .device-deps/old (git archive). Writes under $OUT.
set -uo pipefail
OUT=${OUT:-/tmp/out}
mkdir -p "$OUT"
exec > >(tee "$OUT/regress.txt") 2>&1
nvidia-smi --query-gpu=name,clocks.sm,clocks.max.sm,power.limit,temperature.gpu --format=csv
flags="-DCMAKE_PREFIX_PATH=$PWD/.device-deps/usr -DPRT_WITH_PCL=OFF -DPRT_WITH_OPENMESH=OFF -DPRT_WITH_OIIO=OFF -DPRT_WITH_PYTHON=OFF -DPRT_WITH_GLFW=OFF -DCMAKE_BUILD_TYPE=Release"
for v in a164496 b964ab50; do
    mkdir -p /tmp/$v && tar -xzf .device-deps/old/$v.tar.gz -C /tmp/$v
    (cmake -S /tmp/$v -B /tmp/$v/build $flags >/tmp/$v.cmake.txt 2>&1 &&
     cmake --build /tmp/$v/build -j16 --target prt-bench >/tmp/$v.build.txt 2>&1) || { tail -20 /tmp/$v.build.txt; }
done
cmake --build build-dev -j16 --target prt-bench >/dev/null 2>&1
for round in 1 2; do
    for b in /tmp/a164496/build/bin/prt-bench /tmp/b964ab50/build/bin/prt-bench build-dev/bin/prt-bench; do
        echo "== $b (round $round)"
        $b --scenarios primary,shadow,reflect4 -q --json /tmp/r.json >/dev/null 2>&1
        python3 -c "
import json; d = json.load(open('/tmp/r.json'))
print(d.get('device'), [(s.get('name', s.get('scenario')), round(s['grays_per_s'], 3), round(s['median_ms'], 3)) for s in d['scenarios']])"
    done
done
