# Samples, every 0.25 s until killed, the whole machine's CPU time split (/proc/stat: user, system,
# idle, iowait, steal, as busy cores) and writes one line each: seconds since $T0 (epoch), then those.
# Used by gpu-f1.sh beside nvidia-smi's own sampling of the GPU's load.
import os, sys, time
t0 = float(os.environ.get("T0", time.time()))
def cpu():
    f = open("/proc/stat").readline().split()[1:]
    v = [int(x) for x in f]  # user nice system idle iowait irq softirq steal ...
    return v[0] + v[1], v[2] + v[5] + v[6], v[3], v[4], v[7] if len(v) > 7 else 0
hz = os.sysconf("SC_CLK_TCK"); out = open(sys.argv[1], "w"); last = cpu(); lt = time.time()
out.write("t user sys idle iowait steal (cores busy in each over the sample)\n")
while True:
    time.sleep(0.25); now = cpu(); nt = time.time(); dt = nt - lt
    out.write("%.2f " % (nt - t0) + " ".join("%.2f" % ((a - b) / hz / dt) for a, b in zip(now, last)) + "\n")
    out.flush(); last, lt = now, nt
