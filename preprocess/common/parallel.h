// PointRT preprocess: a minimal fork-join helper over std::thread shared by the tools (prt-radii,
// prt-octree, prt-cull, prt-mls, prt-iso). Work is handed out in chunks through an atomic counter
// (dynamic scheduling); the first exception thrown by any worker is rethrown on the calling thread.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace prt::pre {

/// The number of worker threads to use: `requested`, or every hardware thread when 0.
inline unsigned resolve_threads(unsigned requested) {
    if (requested > 0) return requested;
    const unsigned hw = std::thread::hardware_concurrency();
    return hw > 0 ? hw : 1;
}

/// Calls `body(begin, end, worker)` on chunks of [0, count) of at most `chunk` items, from
/// `threads` workers (worker 0 is the calling thread). Chunks are taken in increasing order.
/// Rethrows the first exception any call threw, after every worker stopped.
template <class Body>
void parallel_chunks(std::size_t count, std::size_t chunk, unsigned threads, Body&& body) {
    chunk = std::max<std::size_t>(chunk, 1);
    const std::size_t chunks = (count + chunk - 1) / chunk;
    const unsigned workers =
        static_cast<unsigned>(std::min<std::size_t>(std::max(threads, 1u), std::max<std::size_t>(chunks, 1)));
    std::atomic<std::size_t> next{0};
    std::atomic<bool> failed{false};
    std::exception_ptr error;
    std::mutex error_mutex;
    auto work = [&](unsigned worker) {
        try {
            for (;;) {
                if (failed.load(std::memory_order_relaxed)) return;
                const std::size_t c = next.fetch_add(1, std::memory_order_relaxed);
                if (c >= chunks) return;
                const std::size_t begin = c * chunk;
                body(begin, std::min(count, begin + chunk), worker);
            }
        } catch (...) {
            std::lock_guard<std::mutex> lock(error_mutex);
            if (!error) error = std::current_exception();
            failed.store(true);
        }
    };
    std::vector<std::thread> pool;
    pool.reserve(workers > 0 ? workers - 1 : 0);
    for (unsigned w = 1; w < workers; ++w) pool.emplace_back(work, w);
    work(0);
    for (std::thread& t : pool) t.join();
    if (error) std::rethrow_exception(error);
}

}  // namespace prt::pre
