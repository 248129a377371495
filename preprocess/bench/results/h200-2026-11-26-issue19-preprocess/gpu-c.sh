#!/bin/bash
# Issue 19, round C: where prt-iso and prt-octree spend their time on 1, 2 and 16 cores
# (--stats-json), on scripts/bench-preprocess.sh's 1M-point room.
set -uo pipefail
OUT=${OUT:-/tmp/out}
mkdir -p "$OUT"
exec > >(tee "$OUT/c.txt") 2>&1
flags="-DCMAKE_PREFIX_PATH=$PWD/.device-deps/usr -DPRT_WITH_PCL=OFF -DPRT_WITH_OPENMESH=OFF -DPRT_WITH_OIIO=OFF -DPRT_WITH_PYTHON=OFF -DPRT_WITH_GLFW=OFF -DCMAKE_BUILD_TYPE=Release"
t0=$SECONDS
cmake -S . -B build-dev $flags >/tmp/c.cmake.txt 2>&1 &&
    cmake --build build-dev -j16 --target prt-import prt-radii prt-octree prt-cull prt-iso >/tmp/c.build.txt 2>&1 ||
    { grep -E "error" -A3 /tmp/c.build.txt | head -30; exit 1; }
echo "build: $((SECONDS - t0)) s"
KEEP=1 bash scripts/bench-preprocess.sh build-dev 1000000 16 1 | tee $OUT/preprocess16.txt
w=$(sed -n 's/^# work folder: //p' $OUT/preprocess16.txt)
for t in 1 2 16; do
    /usr/bin/time -f "prt-iso $t threads: %e s wall, %U s user, %M KB" taskset -c 0-$((t - 1)) \
        build-dev/bin/prt-iso $w/prt-cull.pool -o /tmp/iso.pool -q --stats-json $OUT/iso-$t.json
    /usr/bin/time -f "prt-octree $t threads: %e s wall, %U s user, %M KB" taskset -c 0-$((t - 1)) \
        build-dev/bin/prt-octree $w/prt-radii.pool -o /tmp/oct.pool -q --stats-json $OUT/octree-$t.json
    /usr/bin/time -f "prt-import $t threads: %e s wall, %U s user, %M KB" taskset -c 0-$((t - 1)) \
        build-dev/bin/prt-import $w/room.ply -o /tmp/imp.pool
done
python3 - $OUT <<'PY'
import json, sys
out = sys.argv[1]
for tool in ("iso", "octree"):
    rows = {t: json.load(open(f"{out}/{tool}-{t}.json")) for t in (1, 2, 16)}
    keys = [k for k, v in rows[1].items() if "second" in k or k.startswith("t_") or k.endswith("_s")]
    print(tool, "keys:", list(rows[1].keys())[:60])
    for k in keys:
        print(f"  {k:30s}", " ".join(f"{rows[t][k]:8.3f}" for t in (1, 2, 16)))
PY
ls -la $w
echo "ALL_DONE $((SECONDS - t0)) s"
