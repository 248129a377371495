// The shared algorithm layer (issue 16): prt/parallel.h's fork-join, the Morton codes (morton.h),
// the radix sort (radix_sort.h), the exact kd-tree (kd_tree.h) and the outward float rounding
// (float_round.h), each against a brute-force or standard-library reference; the spill files'
// background releaser (spill_file.h).
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <numeric>
#include <random>
#include <set>
#include <stdexcept>
#include <thread>
#include <vector>

#include "buffer.h"
#include "float_round.h"
#include "kd_tree.h"
#include "morton.h"
#include "point_cloud.h"
#include "prt/parallel.h"
#include "radix_sort.h"
#include "spill_file.h"

namespace {

using namespace prt;

TEST(Parallel, EveryIndexOnceWhateverTheThreadCount) {
    for (unsigned threads : {1u, 2u, 7u})
        for (std::size_t count : {std::size_t{0}, std::size_t{1}, std::size_t{999}, std::size_t{4096}}) {
            std::vector<std::atomic<int>> seen(count);
            std::atomic<unsigned> max_worker{0};
            parallel_chunks(count, 100, threads, [&](std::size_t b, std::size_t e, unsigned worker) {
                EXPECT_LE(e - b, 100u);
                for (std::size_t i = b; i < e; ++i) ++seen[i];
                unsigned m = max_worker.load();
                while (worker > m && !max_worker.compare_exchange_weak(m, worker)) {
                }
            });
            for (std::size_t i = 0; i < count; ++i) EXPECT_EQ(seen[i].load(), 1) << i;
            EXPECT_LT(max_worker.load(), threads);
        }
}

TEST(Parallel, RethrowsAWorkersException) {
    EXPECT_THROW(parallel_chunks(1000, 10, 3,
                                 [](std::size_t b, std::size_t, unsigned) {
                                     if (b == 500) throw std::runtime_error("chunk 50");
                                 }),
                 std::runtime_error);
}

TEST(Parallel, SelectKeepsTheInputOrder) {
    const std::size_t n = 100000;
    std::vector<std::size_t> out(n, ~std::size_t{0});
    const std::size_t kept = parallel_select(
        n, 3, [](std::size_t i) { return i % 7 == 3; }, [&](std::size_t r, std::size_t i) { out[r] = i; });
    ASSERT_EQ(kept, (n - 3 + 6) / 7);
    for (std::size_t r = 0; r < kept; ++r) EXPECT_EQ(out[r], 7 * r + 3);
}

#if defined(__linux__)
// Tools started under taskset or a cgroup cpuset use the cores they were given, not every core of
// the machine (bench-preprocess.sh pins the tools this way).
TEST(Parallel, ZeroThreadsMeansTheCoresTheAffinityMaskAllows) {
    cpu_set_t saved;
    ASSERT_EQ(sched_getaffinity(0, sizeof(saved), &saved), 0);
    EXPECT_EQ(available_cores(), static_cast<unsigned>(CPU_COUNT(&saved)));
    int first = 0;
    while (!CPU_ISSET(first, &saved)) ++first;
    cpu_set_t one;
    CPU_ZERO(&one);
    CPU_SET(first, &one);
    ASSERT_EQ(sched_setaffinity(0, sizeof(one), &one), 0);
    const unsigned pinned = available_cores(), resolved = resolve_threads(0), asked = resolve_threads(5);
    ASSERT_EQ(sched_setaffinity(0, sizeof(saved), &saved), 0);
    EXPECT_EQ(pinned, 1u);
    EXPECT_EQ(resolved, 1u);
    EXPECT_EQ(asked, 5u);  // an explicit count is kept
}
#endif

TEST(FloatRound, NextFloatIsStdNextafterAndRoundingIsOutward) {
    // next_float_down / up on the bits equal std::nextafter (bit for bit, signed zeros and
    // subnormals included); round_down / round_up give the float nearest v on its side.
    constexpr float inf = std::numeric_limits<float>::infinity();
    auto bits = [](float f) {
        std::uint32_t u;
        std::memcpy(&u, &f, sizeof u);
        return u;
    };
    std::vector<float> values = {0.0f,
                                 -0.0f,
                                 std::numeric_limits<float>::denorm_min(),
                                 -std::numeric_limits<float>::denorm_min(),
                                 std::numeric_limits<float>::min(),
                                 -std::numeric_limits<float>::min(),
                                 std::numeric_limits<float>::max(),
                                 -std::numeric_limits<float>::max(),
                                 1.0f,
                                 -1.0f,
                                 0.1f,
                                 -3e-39f};
    std::mt19937 rng(7);
    std::uniform_int_distribution<std::uint32_t> any;
    for (int i = 0; i < 200000; ++i) {
        const std::uint32_t u = any(rng);
        float f;
        std::memcpy(&f, &u, sizeof f);
        if (std::isfinite(f)) values.push_back(f);
    }
    for (const float f : values) {
        ASSERT_EQ(bits(pre::next_float_down(f)), bits(std::nextafter(f, -inf))) << f;
        ASSERT_EQ(bits(pre::next_float_up(f)), bits(std::nextafter(f, inf))) << f;
    }
    EXPECT_EQ(pre::next_float_down(inf), std::numeric_limits<float>::max());
    EXPECT_EQ(pre::next_float_up(-inf), -std::numeric_limits<float>::max());
    std::uniform_real_distribution<double> mantissa(-1.0, 1.0);
    std::uniform_int_distribution<int> exponent(-160, 140);
    for (int i = 0; i < 200000; ++i) {
        const double v = std::ldexp(mantissa(rng), exponent(rng));
        const float lo = pre::round_down(v), hi = pre::round_up(v);
        ASSERT_LE(double(lo), v);
        ASSERT_GE(double(hi), v);
        ASSERT_GT(double(std::nextafter(lo, inf)), v) << v;  // the largest float not above v
        ASSERT_LT(double(std::nextafter(hi, -inf)), v) << v;
    }
    EXPECT_EQ(pre::round_up(1e300), inf);
    EXPECT_EQ(pre::round_down(1e300), std::numeric_limits<float>::max());
    EXPECT_EQ(pre::round_down(-1e300), -inf);
}

TEST(Morton, InterleavesXLowestAndInverts) {
    for (std::uint32_t x : {0u, 1u, 5u, 1023u, (1u << 20), (1u << 21) - 1})
        for (std::uint32_t y : {0u, 2u, 77u, (1u << 20) - 3})
            for (std::uint32_t z : {0u, 3u, 999u, (1u << 21) - 1}) {
                const std::uint64_t m = pre::morton3(x, y, z);
                std::uint64_t expected = 0;
                for (int b = 0; b < 21; ++b)
                    expected |= (std::uint64_t((x >> b) & 1u) << (3 * b)) |
                                (std::uint64_t((y >> b) & 1u) << (3 * b + 1)) |
                                (std::uint64_t((z >> b) & 1u) << (3 * b + 2));
                EXPECT_EQ(m, expected);
                std::uint32_t a, b, c;
                pre::demorton3(m, a, b, c);
                EXPECT_EQ(a, x);
                EXPECT_EQ(b, y);
                EXPECT_EQ(c, z);
            }
    EXPECT_EQ(pre::morton3(1, 0, 0), 1u);  // the child index x | y << 1 | z << 2
    EXPECT_EQ(pre::morton3(0, 1, 0), 2u);
    EXPECT_EQ(pre::morton3(0, 0, 1), 4u);
}

TEST(RadixSort, StableLikeStdStableSort) {
    std::mt19937_64 rng(7);
    for (std::size_t n : {std::size_t{0}, std::size_t{1}, std::size_t{1000}, std::size_t{300000}})
        for (std::uint32_t bits : {12u, 40u, 64u}) {
            std::vector<std::uint64_t> keys(n);
            // few distinct values in the low bits (ties), constant middle digits (skipped passes)
            for (auto& k : keys) k = (rng() & 0xfffu) | (bits > 40 ? (rng() % 3) << 50 : 0);
            std::vector<std::uint32_t> order(n);
            std::iota(order.begin(), order.end(), 0u);
            std::vector<std::uint32_t> expected = order;
            std::stable_sort(expected.begin(), expected.end(),
                             [&](std::uint32_t a, std::uint32_t b) { return keys[a] < keys[b]; });
            std::vector<std::uint64_t> sorted = keys;
            pre::radix_sort(sorted, &order, bits, 3);
            EXPECT_EQ(order, expected) << n << " keys, " << bits << " bits";
            for (std::size_t i = 0; i < n; ++i) EXPECT_EQ(sorted[i], keys[expected[i]]);
        }
}

TEST(RadixSort, RecordsByKey) {
    std::mt19937_64 rng(11);
    std::vector<std::pair<std::uint64_t, std::uint32_t>> v(200000);
    for (std::uint32_t i = 0; i < v.size(); ++i) v[i] = {rng() >> 1, i};
    auto expected = v;
    std::sort(expected.begin(), expected.end());  // distinct indices: the stable order
    pre::radix_sort_by(v, 63, 2, [](const auto& e) { return e.first; });
    EXPECT_EQ(v, expected);
}

/// Brute force: the k nearest points to q other than `skip`, by (squared distance, index).
template <class T>
std::vector<std::pair<T, std::uint32_t>> brute(const std::vector<std::array<T, 3>>& p, const T q[3],
                                               std::uint32_t skip, std::size_t k) {
    std::vector<std::pair<T, std::uint32_t>> d;
    d.reserve(p.size());
    for (std::uint32_t j = 0; j < p.size(); ++j) {
        if (j == skip) continue;
        const T dx = p[j][0] - q[0], dy = p[j][1] - q[1], dz = p[j][2] - q[2];
        d.push_back({dx * dx + dy * dy + dz * dz, j});
    }
    const std::size_t n = std::min(k, d.size());
    std::partial_sort(d.begin(), d.begin() + std::ptrdiff_t(n), d.end());  // the k smallest, sorted
    d.resize(n);
    return d;
}

template <class T>
void check_against_brute_force(unsigned threads) {
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> u(-1, 1);
    std::vector<std::array<T, 3>> p(70000);  // above the size where the top levels build in parallel
    for (auto& q : p) q = {T(u(rng)), T(u(rng)), T(0.1 * u(rng))};
    for (std::size_t i = 0; i < 200; ++i) p[1000 + i] = p[i];                   // duplicates: ties at 0
    for (std::size_t i = 0; i < 50; ++i) p[2000 + i] = {T(0.5), T(0.5), T(0)};  // a pile of 50
    const pre::KdTree<T> tree(
        p.size(), [&](std::size_t i, T c[3]) { std::copy_n(p[i].data(), 3, c); }, threads);
    const std::uint32_t k = 9;
    std::vector<std::uint32_t> index(k);
    std::vector<T> d2(k);
    for (std::uint32_t i = 0; i < p.size(); i += 97) {
        const auto expected = brute(p, p[i].data(), i, k);
        ASSERT_EQ(tree.nearest(i, k, nullptr, index.data(), d2.data()), k);
        for (std::uint32_t j = 0; j < k; ++j) {
            EXPECT_EQ(index[j], expected[j].second) << "point " << i;
            EXPECT_EQ(d2[j], expected[j].first) << "point " << i;
        }
    }
    for (std::uint32_t i : {2000u, 2049u, 1005u}) {  // inside the pile and on a duplicate
        const auto expected = brute(p, p[i].data(), i, k);
        tree.nearest(i, k, nullptr, index.data(), d2.data());
        for (std::uint32_t j = 0; j < k; ++j) EXPECT_EQ(index[j], expected[j].second) << "point " << i;
    }
    // for_each: every point once, the same k-th distance as nearest()
    std::vector<T> kth(p.size(), T(-1));
    tree.for_each(k, threads, [&](std::uint32_t i, const std::uint32_t*, const T* d, std::uint32_t found) {
        ASSERT_EQ(found, k);
        kth[i] = d[k - 1];
    });
    for (std::uint32_t i = 0; i < p.size(); i += 31)
        EXPECT_EQ(kth[i], brute(p, p[i].data(), i, k)[k - 1].first);
    // arbitrary queries, no skip
    for (int t = 0; t < 100; ++t) {
        const T q[3] = {T(1.5 * u(rng)), T(1.5 * u(rng)), T(u(rng))};
        const auto expected = brute(p, q, ~0u, k);
        ASSERT_EQ(tree.search(q, ~0u, k, nullptr, index.data(), d2.data()), k);
        for (std::uint32_t j = 0; j < k; ++j) EXPECT_EQ(index[j], expected[j].second);
    }
}

TEST(KdTree, FloatMatchesBruteForce) {
    check_against_brute_force<float>(1);
    check_against_brute_force<float>(4);
}

TEST(KdTree, DoubleMatchesBruteForce) {
    check_against_brute_force<double>(2);
}

TEST(KdTree, FewPointsAndExclusion) {
    const std::vector<std::array<double, 3>> p = {{0, 0, 0}, {1, 0, 0}, {3, 0, 0}, {0, 2, 0}};
    const pre::KdTree<double> tree(p.size(),
                                   [&](std::size_t i, double c[3]) { std::copy_n(p[i].data(), 3, c); });
    std::uint32_t index[8];
    double d2[8];
    EXPECT_EQ(tree.nearest(0, 8, nullptr, index, d2), 3u);  // fewer points than k
    EXPECT_EQ(index[0], 1u);
    EXPECT_EQ(index[1], 3u);
    EXPECT_EQ(index[2], 2u);
    const std::uint8_t excluded[4] = {0, 1, 0, 0};
    EXPECT_EQ(tree.nearest(0, 2, excluded, index, d2), 2u);
    EXPECT_EQ(index[0], 3u);
    EXPECT_EQ(d2[0], 4.0);
    EXPECT_EQ(tree.point(2)[0], 3.0);
    const pre::KdTree<float> empty(0, [](std::size_t, float*) {});
    EXPECT_EQ(empty.size(), 0u);
}

// buffer.h: large blocks on 2 MiB boundaries (huge pages), small ones from malloc; a LargeVector
// keeps its elements across growth; resize_on_huge_pages zeroes as resize does.
TEST(LargeMemory, LargeBlocksAre2MiBAlignedAndHoldTheirContents) {
    constexpr std::size_t k_huge = std::size_t{2} << 20;
    pre::Buffer<std::uint64_t> big(3 * k_huge / 8 + 5);  // not a whole number of huge pages
    EXPECT_EQ(reinterpret_cast<std::uintptr_t>(big.data()) % k_huge, 0u);
    for (std::size_t i = 0; i < big.size(); ++i) big[i] = i * 7;
    EXPECT_EQ(big[big.size() - 1], (big.size() - 1) * 7);
    pre::Buffer<double> small(10);
    ASSERT_NE(small.data(), nullptr);
    EXPECT_TRUE(pre::Buffer<int>(0).empty());
    EXPECT_THROW(pre::Buffer<std::uint64_t>(std::size_t(-1) / 4), std::bad_array_new_length);

    pre::LargeVector<std::uint32_t> v;
    for (std::uint32_t i = 0; i < 3'000'000; ++i) v.push_back(i ^ 0x5a5au);  // grows past 8 MiB
    EXPECT_EQ(reinterpret_cast<std::uintptr_t>(v.data()) % k_huge, 0u);
    for (std::uint32_t i = 0; i < v.size(); i += 999) ASSERT_EQ(v[i], i ^ 0x5a5au);
    pre::LargeVector<std::uint32_t> w(v.begin(), v.begin() + 100);
    EXPECT_EQ(w.back(), 99u ^ 0x5a5au);

    std::vector<double> z;
    pre::resize_on_huge_pages(z, 1'000'000);
    ASSERT_EQ(z.size(), 1'000'000u);
    EXPECT_TRUE(std::all_of(z.begin(), z.end(), [](double x) { return x == 0.0; }));
    std::vector<int> r{1, 2, 3};
    pre::reserve_on_huge_pages(r, 2'000'000);  // not empty: kept, no advice needed
    EXPECT_EQ(r.size(), 3u);
    EXPECT_EQ(r[2], 3);
    EXPECT_GE(r.capacity(), 2'000'000u);
}

// buffer.h: the prefaulting growths give what resize and reserve give (new elements zero, old ones
// kept, across several growths and thread counts), with the capacity hint kept as room.
TEST(LargeMemory, PrefaultedGrowthKeepsElementsAndZeroesNewOnes) {
    for (const unsigned threads : {1u, 3u, 8u}) {
        pre::LargeVector<std::uint64_t> v;
        pre::resize_prefaulted(v, 10, threads, 1'000'000);  // from empty: the hint is the capacity
        EXPECT_GE(v.capacity(), 1'000'000u);
        std::size_t filled = 0;
        for (const std::size_t n : {std::size_t{10}, std::size_t{900'000}, std::size_t{1'000'000},
                                    std::size_t{1'000'001}, std::size_t{5'000'003}}) {
            pre::resize_prefaulted(v, n, threads);
            ASSERT_EQ(v.size(), n);
            for (std::size_t i = 0; i < filled; ++i) ASSERT_EQ(v[i], i * 3 + 1) << threads << " threads";
            for (std::size_t i = filled; i < n; ++i) {
                ASSERT_EQ(v[i], 0u) << "element " << i << " of " << n << ", " << threads << " threads";
                v[i] = i * 3 + 1;
            }
            filled = n;
        }
        pre::resize_prefaulted(v, 7, threads);  // shrinking is resize
        EXPECT_EQ(v.size(), 7u);
        EXPECT_EQ(v[6], 19u);

        pre::LargeVector<std::uint32_t> w{4, 5, 6};
        pre::reserve_prefaulted(w, 3'000'000, threads);
        EXPECT_GE(w.capacity(), 3'000'000u);
        EXPECT_EQ(w, (pre::LargeVector<std::uint32_t>{4, 5, 6}));
        const std::uint32_t* before = w.data();
        pre::reserve_prefaulted(w, 10, threads);  // smaller than the capacity: nothing
        EXPECT_EQ(w.data(), before);

        std::vector<float> z{1.5f};
        pre::resize_on_huge_pages(z, 3'000'000, threads);
        EXPECT_EQ(z[0], 1.5f);
        EXPECT_TRUE(std::all_of(z.begin() + 1, z.end(), [](float x) { return x == 0.0f; }));
    }
    std::vector<unsigned char> block(5 * 4096 + 17, 0xab);  // prefault writes zeros to a byte per page
    pre::prefault(block.data(), block.size(), 4);
    EXPECT_EQ(block[1], 0xab);
    EXPECT_EQ(std::count(block.begin(), block.end(), 0), 7);  // 6 page starts and the last byte
    pre::prefault(nullptr, 100, 4);  // nothing to touch
}

// point_cloud.h: clean() in parallel (chunks of 32k points, a radix sort of the hashes) against a
// serial reference written here: first occurrences kept in input order, -0 equal to +0, non-finite
// points and zero normals dropped before duplicates are looked for, the kept normals unit.
TEST(Clean, ParallelCleanKeepsTheFirstOccurrencesASerialPassKeeps) {
    std::mt19937 rng(7);
    std::uniform_int_distribution<int> cell(-30, 29);
    std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
    pre::PointCloud cloud;
    for (std::size_t i = 0; i < 300'000; ++i) {  // 216k cells: about a quarter are repeats
        std::array<double, 3> p{cell(rng) * 0.25, cell(rng) * 0.25, cell(rng) * 0.25};
        for (double& c : p)
            if (c == 0.0 && (i & 1)) c = -0.0;  // -0 and +0: the same position
        if (i % 9973 == 0) p[i % 3] = std::numeric_limits<double>::quiet_NaN();
        cloud.positions.push_back(p);
        pool::Float3 n{unit(rng), unit(rng), unit(rng)};
        if (i % 7919 == 0) n = {0.0f, 0.0f, 0.0f};
        cloud.normals.push_back(n);
    }
    const pre::PointCloud input = cloud;
    std::vector<std::size_t> expected;
    std::uint64_t non_finite = 0, zero_normal = 0, duplicates = 0;
    std::set<std::array<double, 3>> seen;  // operator< sees -0 and +0 as equivalent
    for (std::size_t i = 0; i < input.size(); ++i) {
        const auto& p = input.positions[i];
        const auto& n = input.normals[i];
        if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) {
            ++non_finite;
        } else if (n.x == 0.0f && n.y == 0.0f && n.z == 0.0f) {
            ++zero_normal;
        } else if (!seen.insert(p).second) {
            ++duplicates;
        } else {
            expected.push_back(i);
        }
    }
    ASSERT_GT(duplicates, 10'000u);
    std::vector<std::size_t> kept;
    const pre::CleanReport r = pre::clean(cloud, true, &kept);
    EXPECT_EQ(r.input, input.size());
    EXPECT_EQ(r.non_finite, non_finite);
    EXPECT_EQ(r.zero_normal, zero_normal);
    EXPECT_EQ(r.duplicates, duplicates);
    EXPECT_EQ(r.kept, expected.size());
    ASSERT_EQ(kept, expected);
    ASSERT_EQ(cloud.size(), expected.size());
    for (std::size_t j = 0; j < kept.size(); ++j) {
        ASSERT_EQ(cloud.positions[j], input.positions[kept[j]]);
        const pool::Float3& n = cloud.normals[j];
        ASSERT_NEAR(std::sqrt(double(n.x) * n.x + double(n.y) * n.y + double(n.z) * n.z), 1.0, 1e-6);
    }
    EXPECT_EQ(pre::position_hash({0.0, -0.0, 1.0}), pre::position_hash({-0.0, 0.0, 1.0}));
}

/// Open file descriptors of this process (/proc/self/fd).
std::size_t open_files() {
    std::size_t n = 0;
    for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator("/proc/self/fd")) ++n;
    return n;
}

/// SpillReleaser closes what it is handed, from any thread, and its destructor waits for it; the
/// files' contents stay readable until they are handed over.
TEST(SpillReleaser, ClosesEveryFileHandedOverByTheTimeItIsGone) {
    const std::filesystem::path dir = std::filesystem::temp_directory_path();
    const std::size_t before = open_files();
    {
        pre::SpillReleaser releaser;
        std::vector<pre::SpillFile> files;
        for (int k = 0; k < 6; ++k) {
            files.emplace_back(dir, 1u << 20, "a test's records");
            std::memset(files.back().data(), k + 1, 1u << 20);
        }
        EXPECT_EQ(before + 6, open_files()) << "a descriptor per spill file";
        std::vector<std::thread> handers;
        for (int t = 0; t < 2; ++t)
            handers.emplace_back([&, t] {
                for (int k = t; k < 6; k += 2) {
                    EXPECT_EQ(std::byte(k + 1), files[std::size_t(k)].data()[(1u << 20) - 1]);
                    releaser.release(std::move(files[std::size_t(k)]));
                    EXPECT_EQ(nullptr, files[std::size_t(k)].data());
                }
            });
        for (std::thread& h : handers) h.join();
    }
    EXPECT_EQ(before, open_files());
}

}  // namespace
