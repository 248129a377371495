# Prints each new stage of a tool's progress on stdin (lines and carriage returns) with the seconds
# since $T0 (epoch), so the lines line up with load.py's and nvidia-smi's samples. Used by gpu-f1.sh.
import os, sys, time
t0 = float(os.environ.get("T0", time.time())); last = None
for line in sys.stdin:
    for part in line.replace("\r", "\n").split("\n"):
        p = part.strip()
        if p and p[:25] != last:
            print("%7.2f %s" % (time.time() - t0, p[:220]), flush=True); last = p[:25]
