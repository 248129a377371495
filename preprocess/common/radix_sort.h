// PointRT preprocess: the one radix sort of the builders (prt-iso's corner slots, the GI octrees'
// sample keys). Host only.
//
// Stable least-significant-digit radix sort (Knuth, TAOCP vol. 3, 5.2.5), 11-bit digits. Each pass
// counts and scatters contiguous blocks of the input in parallel (one block per worker, bucket-major
// then block-minor offsets keep it stable); a pass whose digit is the same for every key is skipped
// (it would not move anything).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "prt/parallel.h"

namespace prt::pre {

/// Sorts `keys` ascending by the low `bits` bits of key_of(keys[i]) (an unsigned 64-bit value),
/// permuting `values` alongside when not null. Stable. Keys and Values: std::vector or pre::Buffer
/// (whose scratch copies stay uninitialised until the parallel scatter first touches them).
/// `threads` 0: every hardware thread (fewer for small inputs: one per 64 Ki keys).
template <class Keys, class Values, class KeyOf>
void radix_sort(Keys& keys, Values* values, std::uint32_t bits, unsigned threads, KeyOf key_of) {
    constexpr std::uint32_t k_digit_bits = 11;
    constexpr std::size_t k_buckets = std::size_t{1} << k_digit_bits;
    const std::size_t n = keys.size();
    const unsigned workers = static_cast<unsigned>(
        std::min<std::size_t>(resolve_threads(threads), std::max<std::size_t>(1, n >> 16)));
    const std::size_t block = (n + workers - 1) / workers;
    Keys tmp_keys(n);
    Values tmp_values(values ? n : 0);
    std::vector<std::size_t> count(workers * k_buckets);
    const std::uint64_t mask = k_buckets - 1;
    for (std::uint32_t shift = 0; shift < bits; shift += k_digit_bits) {
        std::fill(count.begin(), count.end(), 0);
        parallel_chunks(n, block, workers, [&](std::size_t begin, std::size_t end, unsigned) {
            std::size_t* c = &count[(begin / block) * k_buckets];
            for (std::size_t i = begin; i < end; ++i) ++c[(std::uint64_t(key_of(keys[i])) >> shift) & mask];
        });
        std::size_t sum = 0;  // bucket-major, block-minor: stable
        bool one_bucket = false;
        for (std::size_t d = 0; d < k_buckets; ++d) {
            const std::size_t before = sum;
            for (unsigned t = 0; t < workers; ++t) {
                const std::size_t v = count[t * k_buckets + d];
                count[t * k_buckets + d] = sum;
                sum += v;
            }
            one_bucket = one_bucket || (sum - before == n && n > 0);
        }
        if (one_bucket) continue;  // every key has this digit: the pass is the identity
        parallel_chunks(n, block, workers, [&](std::size_t begin, std::size_t end, unsigned) {
            std::size_t* c = &count[(begin / block) * k_buckets];
            for (std::size_t i = begin; i < end; ++i) {
                const std::size_t at = c[(std::uint64_t(key_of(keys[i])) >> shift) & mask]++;
                tmp_keys[at] = keys[i];
                if (values) tmp_values[at] = (*values)[i];
            }
        });
        keys.swap(tmp_keys);
        if (values) values->swap(tmp_values);
    }
}

/// radix_sort of plain unsigned keys (the key is the value itself).
template <class Keys, class Values>
void radix_sort(Keys& keys, Values* values, std::uint32_t bits, unsigned threads) {
    radix_sort(keys, values, bits, threads, [](const auto& k) { return k; });
}

/// radix_sort of records by key_of(record), without a separate value array.
template <class Items, class KeyOf>
void radix_sort_by(Items& items, std::uint32_t bits, unsigned threads, KeyOf key_of) {
    radix_sort(items, static_cast<Items*>(nullptr), bits, threads, key_of);
}

}  // namespace prt::pre
