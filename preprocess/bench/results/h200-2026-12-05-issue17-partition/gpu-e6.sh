#!/usr/bin/env bash
# Issue 17, 2026-12-05 (fifth session): does transparent huge-page allocation drive the count
# pass's spread? main (new2 = 9efa296's prt-bricks) on the 500M room with THP disabled for the
# process (prctl PR_SET_THP_DISABLE, inherited across exec) and enabled, alternating; vmstat sampled.
NAME=e6 TARS="part.tar.xz"
here=$(cd "$(dirname "$0")" && pwd)
. "$here/../h100-2026-12-05-issue17-radii-neighbours/lib500.sh"
p=/tmp/ab/part; x=$p
[ -f $w/s.pool ] || synth
cat > /tmp/nothp.sh <<'X'
#!/bin/sh
exec python3 -c "import ctypes, os, sys; assert ctypes.CDLL(None).prctl(41, 1, 0, 0, 0) == 0; os.execv(sys.argv[1], sys.argv[1:])" "$@"
X
chmod +x /tmp/nothp.sh
cat > /tmp/nothp-bricks <<X
#!/bin/sh
exec /tmp/nothp.sh $p/new2-bricks "\$@"
X
chmod +x /tmp/nothp-bricks
for v in off on off; do
  python3 $here/vmlog.py $out/vm-e6-$v-$SECONDS.txt & vp=$!
  if [ $v = off ]; then line thp-$v /tmp/nothp-bricks; else line thp-$v $p/new2-bricks; fi
  kill $vp; rm -f $w/b-thp-$v.pool
done
echo "ALL_DONE $((SECONDS - t0)) s"
