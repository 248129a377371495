#!/usr/bin/env bash
# Issue 17: CUDA build, ctest -L gpu, then the out-of-core brick build on a 10M-point room against the
# in-core pipeline (CUDA culling in both): equality of the brick sections, time and peak memory per step.
set -uo pipefail
out=${OUT:-/tmp/out}; mkdir -p "$out"
exec > >(tee -a "$out/log17f.txt") 2>&1
nvidia-smi --query-gpu=name --format=csv,noheader; nproc
deps="-DCMAKE_PREFIX_PATH=$PWD/.device-deps/usr -DPRT_WITH_PCL=OFF -DPRT_WITH_OPENMESH=OFF -DPRT_WITH_OIIO=OFF -DPRT_WITH_GLFW=OFF -DCMAKE_BUILD_TYPE=Release"
cmake -S . -B build-dev $deps >/dev/null 2>&1
cmake --build build-dev -j16 >/tmp/build.txt 2>&1 || { grep -E "error" /tmp/build.txt | head -30; }
[ -n "${SKIP_TESTS:-}" ] || (cd build-dev && ctest -L gpu -j4 --timeout 300 --output-on-failure 2>&1 | grep -vE "^\[ +(OK|RUN) +\]" | tail -25) | tee "$out/gpu_tests.txt"
bin=$PWD/build-dev/bin; w=/tmp/w17f; rm -rf $w; mkdir -p $w
N=${N:-10000000}
t() { date +%s.%N; }
step() { local name=$1; shift; local s=$(t); "$@" --stats-json $w/$name.json 2>$w/$name.err; local rc=$?; local e=$(t);
  python3 - "$name" "$s" "$e" "$rc" "$w/$name.json" <<'PY'
import json, sys
name, s, e, rc, path = sys.argv[1], float(sys.argv[2]), float(sys.argv[3]), sys.argv[4], sys.argv[5]
try: j = json.load(open(path))
except Exception: j = {}
print('%-14s rc %s  %7.2f s  %s' % (name, rc, e - s, ' '.join('%s=%s' % (k, j[k]) for k in ('points','cells','max_cell_points','stored_splats','culled_splats','bricks','pool_bytes_per_point','peak_rss_bytes','points_per_second') if k in j)))
PY
}
s0=$(t); $bin/prt-synth room -n $N --colors normal -o $w/s.pool --quiet; echo "synth $(python3 -c "print(round($(t) - $s0, 2))") s"
step radii $bin/prt-radii $w/s.pool -o $w/r.pool --quiet
step octree $bin/prt-octree $w/r.pool -o $w/o.pool --quiet
step cull $bin/prt-cull $w/o.pool -o $w/c.pool --quiet
step bricks $bin/prt-bricks $w/c.pool -o $w/b_in.pool --quiet
step ooc $bin/prt-bricks $w/r.pool -o $w/b_ooc.pool --quiet --cell-points $((N / 6))
step ooc_mem $bin/prt-bricks $w/r.pool -o $w/b_mem.pool --quiet --memory 1G
grep -h "peak\|cells" $w/ooc.err $w/ooc_mem.err | tail -4
python3 .device-deps/cmp_sections.py $w/b_in.pool $w/b_ooc.pool 128,129,130,131,132 | tail -1
python3 .device-deps/cmp_sections.py $w/b_in.pool $w/b_mem.pool 128,129,130,131,132 | tail -1
cp $w/*.json "$out/" 2>/dev/null
ls -l $w
