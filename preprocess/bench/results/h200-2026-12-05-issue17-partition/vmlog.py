# Samples /proc/vmstat and /proc/meminfo every 0.5 s until killed: one line each, seconds since start
# then the deltas of the counters (pages) and the memory figures (MiB). Used by gpu-e3.sh.
import sys, time
keys = ["pgpgin", "pgpgout", "pgmajfault", "pgfault", "allocstall_normal", "pgscan_direct", "pgscan_kswapd",
        "pgsteal_direct", "pgsteal_kswapd", "thp_fault_alloc", "thp_fault_fallback", "pgfree", "compact_stall",
        "compact_success", "compact_fail", "compact_migrate_scanned"]
mem = ["MemFree", "Cached", "Dirty", "Writeback", "AnonPages", "AnonHugePages", "Mapped"]
def vm():
    d = {}
    for l in open("/proc/vmstat"):
        k, v = l.split(); d[k] = int(v)
    return d
def mi():
    d = {}
    for l in open("/proc/meminfo"):
        k, v = l.split(":"); d[k] = int(v.split()[0]) // 1024
    return d
out = open(sys.argv[1], "w"); t0 = time.time(); last = vm()
out.write("t " + " ".join(keys) + " | " + " ".join(mem) + "\n")
while True:
    time.sleep(0.5); now = vm(); m = mi()
    out.write("%.1f " % (time.time() - t0) + " ".join(str(now.get(k, 0) - last.get(k, 0)) for k in keys) + " | " +
              " ".join(str(m.get(k, 0)) for k in mem) + "\n"); out.flush(); last = now
