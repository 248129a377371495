"""Summarizes prt-play's per-pass lines of a --frames N --converge run: frames, how many converged
(a pass with no ray falling back), pass times, and the bricks the unconverged views need."""
import re
import sys

ms, frames, conv, nc, need = [], {}, set(), 0, []
for line in open(sys.argv[1]):
    m = re.search(r'frame (\d+)( pass \d+)?: ([\d.]+) ms.*?(\d+) rays fell back', line)
    if m:
        f = int(m.group(1))
        ms.append(float(m.group(3)))
        frames[f] = frames.get(f, 0) + float(m.group(3))
        if m.group(4) == '0':
            conv.add(f)
    m = re.search(r'holds (\d+) of the (\d+) bricks', line)
    if m:
        nc += 1
        need.append(int(m.group(2)))
a = sorted(ms)
fr = sorted(frames.values())
print('  %d frames, %d converged, %d said not to; %d passes: median %.2f ms, p95 %.2f, max %.2f, '
      'passes over 50 ms: %d; per frame median %.2f; unconverged views need %s bricks' %
      (len(frames), len(conv), nc, len(a), a[len(a) // 2], a[int(len(a) * 0.95)], a[-1],
       sum(x > 50 for x in a), fr[len(fr) // 2], (min(need), max(need)) if need else '-'))
