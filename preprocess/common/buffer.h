// PointRT preprocess: memory for large data. A Buffer is an uninitialised array for scratch data
// filled by parallel loops. std::vector<T>(n) zeroes its n elements on the calling thread before any
// worker starts: for the hundreds of MB of a 10M-sample sort that serial first touch (a page fault
// per 4 KiB, slower still in a VM) cost more than the parallel work itself. A Buffer leaves the
// elements uninitialised, so the pages are first touched by the workers that fill them. A
// LargeVector is a std::vector for tables that grow (octree nodes, corner values). Both ask Linux
// for transparent huge pages when large: a fault per 2 MiB instead of per 4 KiB. A fault still zeroes
// its page, on the thread that touches it first: prefault and resize_prefaulted let the workers of a
// parallel loop touch a block that a serial step (a copy, std::vector's zeroing) fills next.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <new>
#include <span>
#include <type_traits>
#include <utility>
#include <vector>

#if defined(__linux__)
#include <sys/mman.h>
#endif

#include "prt/parallel.h"

namespace prt::pre {

inline constexpr std::size_t k_huge_page = std::size_t{2} << 20;

/// Advises the whole 2 MiB pages inside [p, p + bytes) as transparent huge pages (the system's
/// setting "madvise", Debian's default, gives them only to memory so advised). Advice only: a
/// failure, or a system without it, changes nothing but the page size.
inline void advise_huge_pages([[maybe_unused]] void* p, [[maybe_unused]] std::size_t bytes) {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    const auto begin = reinterpret_cast<std::uintptr_t>(p);
    const std::uintptr_t first = (begin + k_huge_page - 1) / k_huge_page * k_huge_page;
    const std::uintptr_t last = (begin + bytes) / k_huge_page * k_huge_page;
    if (p && last > first) madvise(reinterpret_cast<void*>(first), last - first, MADV_HUGEPAGE);
#endif
}

/// `bytes` of memory (std::free releases it), never null (std::bad_alloc). From 2 MiB up: aligned
/// to 2 MiB, rounded up to whole 2 MiB pages and advised as huge pages (advise_huge_pages).
inline void* allocate_large(std::size_t bytes) {
    void* p = nullptr;
    if (bytes >= k_huge_page) {
        const std::size_t rounded = (bytes + k_huge_page - 1) / k_huge_page * k_huge_page;
        p = std::aligned_alloc(k_huge_page, rounded);
        advise_huge_pages(p, rounded);
    } else {
        p = std::malloc(bytes > 0 ? bytes : 1);
    }
    if (!p) throw std::bad_alloc();
    return p;
}

/// std::vector's allocator with allocate_large's policy (types of fundamental alignment only).
template <class T>
struct LargeAllocator {
    static_assert(alignof(T) <= alignof(std::max_align_t), "LargeAllocator: over-aligned type");
    using value_type = T;
    LargeAllocator() = default;
    template <class U>
    LargeAllocator(const LargeAllocator<U>&) noexcept {}
    T* allocate(std::size_t n) {
        if (n > std::size_t(-1) / sizeof(T)) throw std::bad_array_new_length();
        return static_cast<T*>(allocate_large(n * sizeof(T)));
    }
    void deallocate(T* p, std::size_t) noexcept {
        std::free(p);
    }
    template <class U>
    bool operator==(const LargeAllocator<U>&) const noexcept {
        return true;
    }
};

/// A std::vector whose large blocks are huge pages (LargeAllocator).
template <class T>
using LargeVector = std::vector<T, LargeAllocator<T>>;

/// Touches every page of [p, p + bytes) first, from `threads` workers, each a run of 2 MiB, by
/// writing a zero byte per 4 KiB: the kernel zeroes a fresh page on the thread that faults it, and
/// in a VM that zeroing (clear_page) was a third of prt-iso's time on 2 cores, most of it on the
/// main thread. For storage about to be overwritten only (a fresh block, a vector's spare capacity).
/// One thread: nothing (the writes that follow fault the pages on that thread anyway).
inline void prefault(void* p, std::size_t bytes, unsigned threads) {
    if (p == nullptr || bytes == 0 || threads <= 1) return;
    constexpr std::size_t k_page = 4096;
    auto* const base = static_cast<unsigned char*>(p);
    const std::size_t pages = (bytes + k_page - 1) / k_page;
    parallel_chunks(pages, k_huge_page / k_page, threads, [&](std::size_t b, std::size_t e, unsigned) {
        for (std::size_t i = b; i < e; ++i) *static_cast<volatile unsigned char*>(base + i * k_page) = 0;
    });
    *static_cast<volatile unsigned char*>(base + bytes - 1) = 0;
}

/// v.reserve(capacity) with the moved elements' new pages touched by `threads` workers first
/// (prefault) instead of by the copy on the calling thread.
template <class T>
void reserve_prefaulted(LargeVector<T>& v, std::size_t capacity, unsigned threads) {
    static_assert(std::is_trivially_copyable_v<T>, "reserve_prefaulted: plain data only");
    if (capacity <= v.capacity()) return;
    LargeVector<T> grown;
    grown.reserve(capacity);
    prefault(grown.data(), v.size() * sizeof(T), threads);
    grown.insert(grown.end(), v.begin(), v.end());
    v.swap(grown);
}

/// v.resize(n), the new elements' pages first touched by `threads` workers (prefault) rather than
/// by resize's zeroing on the calling thread; a growth past the capacity takes max(n, 2 x capacity,
/// `capacity_hint`) (reserve_prefaulted). The hint is address space until used: room for a later
/// serial growth (the ISO closure's) without another copy.
template <class T>
void resize_prefaulted(LargeVector<T>& v, std::size_t n, unsigned threads, std::size_t capacity_hint = 0) {
    if (n > v.capacity()) reserve_prefaulted(v, std::max({n, 2 * v.capacity(), capacity_hint}), threads);
    if (n > v.size()) prefault(v.data() + v.size(), (n - v.size()) * sizeof(T), threads);
    v.resize(n);
}

template <class T>
class Buffer {
    static_assert(std::is_trivially_copyable_v<T> && std::is_trivially_destructible_v<T>,
                  "Buffer holds plain data only");

public:
    Buffer() = default;
    /// `n` uninitialised elements.
    explicit Buffer(std::size_t n) : m_size(n) {
        static_assert(alignof(T) <= alignof(std::max_align_t), "Buffer: over-aligned type");
        if (n == 0) return;
        if (n > std::size_t(-1) / sizeof(T)) throw std::bad_array_new_length();
        m_data = static_cast<T*>(allocate_large(n * sizeof(T)));
    }
    Buffer(Buffer&& o) noexcept
        : m_data(std::exchange(o.m_data, nullptr)), m_size(std::exchange(o.m_size, 0)) {}
    Buffer& operator=(Buffer&& o) noexcept {
        swap(o);
        return *this;
    }
    Buffer(const Buffer&) = delete;
    Buffer& operator=(const Buffer&) = delete;
    ~Buffer() {
        std::free(m_data);
    }

    void swap(Buffer& o) noexcept {
        std::swap(m_data, o.m_data);
        std::swap(m_size, o.m_size);
    }
    std::size_t size() const {
        return m_size;
    }
    bool empty() const {
        return m_size == 0;
    }
    T* data() {
        return m_data;
    }
    const T* data() const {
        return m_data;
    }
    T& operator[](std::size_t i) {
        return m_data[i];
    }
    const T& operator[](std::size_t i) const {
        return m_data[i];
    }
    T* begin() {
        return m_data;
    }
    T* end() {
        return m_data + m_size;
    }
    const T* begin() const {
        return m_data;
    }
    const T* end() const {
        return m_data + m_size;
    }
    operator std::span<const T>() const {
        return {m_data, m_size};
    }

private:
    T* m_data = nullptr;
    std::size_t m_size = 0;
};

/// v.reserve(n) for an empty std::vector of another allocator (the formats' model vectors): the
/// new block is advised as huge pages (advise_huge_pages) before the caller fills it.
template <class T, class A>
void reserve_on_huge_pages(std::vector<T, A>& v, std::size_t n) {
    const bool fresh = v.capacity() < n;
    v.reserve(n);
    if (fresh && v.empty()) advise_huge_pages(v.data(), v.capacity() * sizeof(T));
}

/// v.resize(n) after reserve_on_huge_pages; resize zeroes the elements on the calling thread, after
/// `threads` workers touched their pages (prefault).
template <class T, class A>
void resize_on_huge_pages(std::vector<T, A>& v, std::size_t n, unsigned threads = 1) {
    reserve_on_huge_pages(v, n);
    if (n > v.size()) prefault(v.data() + v.size(), (n - v.size()) * sizeof(T), threads);
    v.resize(n);
}

}  // namespace prt::pre
