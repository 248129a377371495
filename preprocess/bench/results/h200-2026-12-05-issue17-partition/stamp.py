# Prints each new stage of a tool's progress on stdin (lines and carriage returns) with the seconds
# since this script started. Used by gpu-e3.sh.
import sys, time
t0 = time.time(); last = None
for line in sys.stdin:
    for part in line.replace("\r", "\n").split("\n"):
        p = part.strip()
        if p and p[:25] != last:
            print("%7.2f %s" % (time.time() - t0, p[:200]), flush=True); last = p[:25]
