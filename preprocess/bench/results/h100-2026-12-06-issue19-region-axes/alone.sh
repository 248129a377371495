# Sourced after lib500.sh (which sets $w): alone LABEL BINARY SCENARIOS ARGS... runs each scenario of
# prt-bench in its own process (1024x1024, 30 frames after 5) and prints Grays/s and leaves per ray.
alone() {
  local label=$1 bin=$2 scs=$3; shift 3; local line="$label"
  for sc in ${scs//,/ }; do
    $bin --backend cuda --frames 30 --warmup 5 --json $w/b.json "$@" --scenarios $sc > /dev/null 2> $w/err.txt \
      || { line="$line $sc failed: $(tail -1 $w/err.txt)"; continue; }
    line="$line $(python3 -c "import json; s=json.load(open('$w/b.json'))['scenarios'][0]; print('%s %.3f [%.1f l]' % (s['name'], s['grays_per_s'], s['leaves_per_ray']))")"
  done
  echo "$line"
}
# pools: the 1M room (prt-bench's), culled, its ISO; the 10M sphere, culled, its ISO.
make_pools() {
  local x=$1 q=--quiet
  $x/prt-bench --backend cuda --save-pool $w/room.pool --frames 1 --warmup 0 --scenarios primary $q > /dev/null 2>&1
  $x/prt-cull $w/room.pool -o $w/croom.pool $q && $x/prt-iso $w/croom.pool -o $w/iroom.pool $q
  $x/prt-synth sphere -n 10000000 -o $w/s10.pool $q && $x/prt-radii $w/s10.pool -o $w/s10.pool --backend cuda $q \
    && $x/prt-octree $w/s10.pool -o $w/s10.pool $q && $x/prt-cull $w/s10.pool -o $w/cs10.pool $q \
    && $x/prt-iso $w/cs10.pool -o $w/is10.pool $q
}
# al LABEL SCENARIOS ARGS...: each scenario of prt-bench $nb alone in its own process (1024x1024,
# median of 100 frames after 10), its Grays/s, and its leaves per ray with AL_LEAVES=1.
al() {
  local label=$1 scs=$2; shift 2; local line="$label"
  for sc in ${scs//,/ }; do
    $nb --backend cuda --frames 100 --warmup 10 --json $w/b.json "$@" --scenarios $sc > /dev/null 2> $w/err.txt \
      || { line="$line $sc failed: $(tail -1 $w/err.txt)"; continue; }
    line="$line $(python3 -c "import json; s=json.load(open('$w/b.json'))['scenarios'][0]; print('%s %.3f' % (s['name'], s['grays_per_s']) + (' [%.1f l]' % s['leaves_per_ray'] if '${AL_LEAVES:-0}' == '1' else ''))")"
  done
  echo "$line"
}
# make_sphere1 TOOLS: the 1M-point sphere ($w/s1.pool) and its culled octree ($w/cs1.pool).
make_sphere1() {
  local x=$1 q=--quiet
  $x/prt-synth sphere -n 1000000 -o $w/s1.pool $q && $x/prt-radii $w/s1.pool -o $w/s1.pool --backend cuda $q \
    && $x/prt-octree $w/s1.pool -o $w/s1.pool $q && $x/prt-cull $w/s1.pool -o $w/cs1.pool $q
}
