// PointRT preprocess: an uninitialised array for large scratch data filled by parallel loops.
// std::vector<T>(n) zeroes its n elements on the calling thread before any worker starts: for the
// hundreds of MB of a 10M-sample sort that serial first touch (a page fault per 4 KiB, slower still
// in a VM) cost more than the parallel work itself. A Buffer leaves the elements uninitialised, so
// the pages are first touched by the workers that fill them, and on Linux asks for transparent huge
// pages when large (a fault per 2 MiB).
#pragma once

#include <cstddef>
#include <cstdlib>
#include <new>
#include <span>
#include <type_traits>
#include <utility>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace prt::pre {

template <class T>
class Buffer {
    static_assert(std::is_trivially_copyable_v<T> && std::is_trivially_destructible_v<T>,
                  "Buffer holds plain data only");

public:
    Buffer() = default;
    /// `n` uninitialised elements.
    explicit Buffer(std::size_t n) : m_size(n) {
        if (n == 0) return;
        const std::size_t bytes = n * sizeof(T);
        constexpr std::size_t k_huge = std::size_t{2} << 20;
        if (bytes >= 4 * k_huge && alignof(T) <= k_huge) {
            const std::size_t rounded = (bytes + k_huge - 1) / k_huge * k_huge;
            m_data = static_cast<T*>(std::aligned_alloc(k_huge, rounded));
#if defined(__linux__) && defined(MADV_HUGEPAGE)
            if (m_data) madvise(m_data, rounded, MADV_HUGEPAGE);  // advice only: failure is harmless
#endif
        } else {
            m_data = static_cast<T*>(std::malloc(bytes));
        }
        if (!m_data) throw std::bad_alloc();
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

}  // namespace prt::pre
