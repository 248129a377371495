#!/bin/bash
set -uo pipefail
OUT=${OUT:-/tmp/out}; mkdir -p "$OUT"; exec > >(tee "$OUT/r3.txt") 2>&1
t0=$SECONDS
cmake --build /tmp/bv1 -j16 --target prt-bench >/tmp/v3.build.txt 2>&1 || { echo FAIL; grep error /tmp/v3.build.txt | head; }
echo "built in $((SECONDS - t0)) s"
summ() { python3 -c "
import json,sys; d = json.load(open('$1'))
print('$2', [(s.get('name'), round(s['grays_per_s'], 3), round(s.get('leaves_per_ray', 0), 2), round(s.get('splat_tests_per_ray', 0), 2)) for s in d['scenarios']])" 2>&1 | tail -1; }
for round in 1 2; do
  for v in v1 v2 head; do
    rm -f /tmp/r.json
    /tmp/b$v/bin/prt-bench --scenarios primary,shadow,reflect4,full4 --frames 50 -q --json /tmp/r.json >/tmp/run.txt 2>&1 || tail -2 /tmp/run.txt
    cp /tmp/r.json $OUT/bench-$v-r$round.json
    summ /tmp/r.json "$v(v1=v3) synthetic r$round"
  done
done
echo "ALL_DONE $((SECONDS - t0)) s"
