// Test-only: the process's CPU time for the CPU benchmarks (iso-bench, mls-bench).
#pragma once

#include <time.h>

namespace prt::test {

/// CPU seconds of the whole process (all threads): on a machine shared with other jobs this is
/// steadier than wall time, which also counts the time the benchmark waits for a core.
inline double cpu_seconds() {
    timespec ts{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

}  // namespace prt::test
