// Resource limits (issue 10): a header that claims 10^15 points (PLY element counts, PCD POINTS and
// WIDTH x HEIGHT, OFF counts, pool section counts, patch and vertex counts of patch files) is
// refused before anything is allocated for
// it: fast, with one line, never std::bad_alloc. This binary replaces the global operator new to
// record the largest single request made while a reader runs; readers may allocate small fixed
// buffers, but nothing that grows with the claimed count.
//
// XYZ and OBJ text have no header counts (their arrays grow with the lines actually read) and the
// scene JSON has no counts at all, so they have no case here; their fuzz targets cover them.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <new>
#include <string>
#include <vector>

#include "fuzz_entries.h"
#include "prt/formats/patch_layout.h"
#include "prt/formats/pool.h"

namespace {

std::atomic<bool> g_armed{false};
std::atomic<std::size_t> g_largest{0};
std::atomic<std::uint64_t> g_total{0};

void* counted(std::size_t size) {
    if (g_armed.load(std::memory_order_relaxed)) {
        std::size_t prev = g_largest.load(std::memory_order_relaxed);
        while (size > prev && !g_largest.compare_exchange_weak(prev, size)) {
        }
        g_total.fetch_add(size, std::memory_order_relaxed);
    }
    return std::malloc(size ? size : 1);
}

}  // namespace

// Replacements of the global allocation functions (C++ [replacement.functions]); the aligned
// forms keep their library definitions.
void* operator new(std::size_t size) {
    if (void* p = counted(size)) return p;
    throw std::bad_alloc();
}
void* operator new[](std::size_t size) {
    if (void* p = counted(size)) return p;
    throw std::bad_alloc();
}
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
    return counted(size);
}
void* operator new[](std::size_t size, const std::nothrow_t&) noexcept {
    return counted(size);
}
void operator delete(void* p) noexcept {
    std::free(p);
}
void operator delete[](void* p) noexcept {
    std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
    std::free(p);
}
void operator delete[](void* p, std::size_t) noexcept {
    std::free(p);
}
void operator delete(void* p, const std::nothrow_t&) noexcept {
    std::free(p);
}
void operator delete[](void* p, const std::nothrow_t&) noexcept {
    std::free(p);
}

namespace {

using prt::fuzz::Result;
using prt::fuzz::Target;

constexpr std::uint64_t k_claim = 1000000000000000ull;  // 10^15
/// Largest single allocation a reader may make while refusing a claim: a fixed buffer (the ASCII
/// PLY reader starts with 2^16 rows, about 3 MB), never anything proportional to the claim.
constexpr std::size_t k_allocation_limit = 16u << 20;
/// "Fails fast": generous for a sanitizer build on a loaded machine; reading the claimed data
/// would take hours.
constexpr double k_time_limit_seconds = 2.0;

struct Measured {
    Result result;
    std::size_t largest = 0;
    double seconds = 0;
};

Measured measure(Target target, const std::string& bytes) {
    (void)prt::fuzz::scratch_dir();  // its own allocations are not the reader's
    Measured m;
    g_largest = 0;
    g_total = 0;
    const auto t0 = std::chrono::steady_clock::now();
    g_armed = true;
    try {
        m.result =
            prt::fuzz::run(target, {reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()});
    } catch (...) {
        g_armed = false;
        throw;
    }
    g_armed = false;
    m.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    m.largest = g_largest;
    return m;
}

/// The claim is refused with one line containing `expected`, quickly, without a large allocation.
void expect_refused(Target target, const std::string& bytes, const std::string& expected) {
    if (!prt::fuzz::available(target)) GTEST_SKIP() << "this build lacks PCL or OpenMesh";
    Measured m;
    ASSERT_NO_THROW(m = measure(target, bytes)) << "a claim must be a prt::Error, not std::bad_alloc";
    EXPECT_FALSE(m.result.accepted);
    EXPECT_EQ(m.result.violation, "");  // one line, naming the input
    EXPECT_NE(m.result.message.find(expected), std::string::npos) << m.result.message;
    EXPECT_LT(m.largest, k_allocation_limit) << "largest allocation " << m.largest << " bytes";
    EXPECT_LT(m.seconds, k_time_limit_seconds);
}

std::string ply_header(const char* format, const std::string& elements) {
    return std::string("ply\nformat ") + format + " 1.0\n" + elements + "end_header\n";
}

const std::string k_xyz_float = "property float x\nproperty float y\nproperty float z\n";
const std::string k_count = std::to_string(k_claim);

TEST(ResourceLimits, PlyBinaryVertexCount) {
    expect_refused(Target::ply,
                   ply_header("binary_little_endian", "element vertex " + k_count + "\n" + k_xyz_float) +
                       std::string(24, '\0'),
                   "header declares " + k_count + " vertices but the data ends after 2");
}

TEST(ResourceLimits, PlyBinaryVertexRowsWithAList) {
    expect_refused(Target::ply,
                   ply_header("binary_big_endian", "element vertex " + k_count + "\n" + k_xyz_float +
                                                       "property list uchar float extra\n") +
                       std::string(13, '\0'),
                   "header declares " + k_count + " vertices but the data ends after 1");
}

TEST(ResourceLimits, PlyAsciiVertexCount) {
    expect_refused(Target::ply,
                   ply_header("ascii", "element vertex " + k_count + "\n" + k_xyz_float) + "1 2 3\n",
                   "header declares " + k_count + " vertices but the data ends after 1");
}

TEST(ResourceLimits, PlyFaceCountAfterTheVertices) {
    expect_refused(
        Target::ply,
        ply_header("binary_little_endian", "element vertex 1\n" + k_xyz_float + "element face " + k_count +
                                               "\nproperty list uchar int vertex_indices\n") +
            std::string(12, '\0') + std::string("\x03\0\0\0\0\0\0\0\0\0\0\0\0", 13),
        "header declares " + k_count + " 'face' rows but the data ends after 1");
}

TEST(ResourceLimits, PlyMeshFaceCountBeforeOpenMesh) {
    expect_refused(Target::ply_mesh,
                   ply_header("ascii", "element vertex 3\n" + k_xyz_float + "element face " + k_count +
                                           "\nproperty list uchar int vertex_indices\n") +
                       "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
                   "header declares " + k_count + " 'face' rows but the data ends after 1");
}

std::string pcd(const std::string& dims, const std::string& data, const std::string& body) {
    return "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n" + dims + "DATA " + data + "\n" +
           body;
}

TEST(ResourceLimits, PcdPointsBinary) {
    expect_refused(Target::pcd,
                   pcd("WIDTH 1\nHEIGHT 1\nPOINTS " + k_count + "\n", "binary", std::string(12, '\0')),
                   "POINTS " + k_count + " is not WIDTH 1 x HEIGHT 1");
}

TEST(ResourceLimits, PcdWidthBinary) {
    expect_refused(
        Target::pcd,
        pcd("WIDTH " + k_count + "\nHEIGHT 1\nPOINTS " + k_count + "\n", "binary", std::string(12, '\0')),
        "WIDTH " + k_count + " x HEIGHT 1: each must be at most 4294967295");
}

TEST(ResourceLimits, PcdWidthTimesHeightBinary) {
    // 31622776 x 31622777 = 1.0000000e15 points, each dimension a valid PCL uint32.
    expect_refused(Target::pcd, pcd("WIDTH 31622776\nHEIGHT 31622777\n", "binary", std::string(12, '\0')),
                   "header declares 999999993568952 points but the data ends after 1");
}

TEST(ResourceLimits, PcdWidthTimesHeightAscii) {
    expect_refused(Target::pcd, pcd("WIDTH 31622776\nHEIGHT 31622777\n", "ascii", "1 2 3\n"),
                   "header declares 999999993568952 points but the data has 1 lines");
}

TEST(ResourceLimits, PcdWidthTimesHeightWrapsTo64Bits) {
    // 2^31 x 2^31 points of 12 bytes: 2^62 x 12 overflows 64 bits (to 0 bytes): the claim must be
    // refused, not compared after the overflow.
    expect_refused(Target::pcd, pcd("WIDTH 2147483648\nHEIGHT 2147483648\n", "binary", std::string(12, '\0')),
                   "4611686018427387904 points");
}

TEST(ResourceLimits, PcdWidthAndHeightBeyondPcl) {
    // 2^32 x 2^32 wraps to 0 points in 64 bits; PCL keeps WIDTH and HEIGHT in 32 bits.
    expect_refused(Target::pcd, pcd("WIDTH 4294967296\nHEIGHT 4294967296\n", "binary", std::string(12, '\0')),
                   "WIDTH 4294967296");
}

TEST(ResourceLimits, PcdBinaryCompressedSizeWords) {
    // 2^31 x 2^31 points of 12 bytes wrap to 0 bytes in 64 bits, and the size words say 0 bytes.
    std::string words(8, '\0');
    expect_refused(Target::pcd, pcd("WIDTH 2147483648\nHEIGHT 2147483648\n", "binary_compressed", words),
                   "4611686018427387904 points");
}

TEST(ResourceLimits, PcdBinaryCompressedTenToTheFifteen) {
    std::string words(8, '\0');
    expect_refused(Target::pcd, pcd("WIDTH 31622776\nHEIGHT 31622777\n", "binary_compressed", words),
                   "999999993568952 points");
}

TEST(ResourceLimits, PcdAsciiValuesPerPoint) {
    // One ASCII point of 4294967295 values (COUNT): PCL would allocate 17 GB before reading it.
    expect_refused(Target::pcd,
                   "VERSION 0.7\nFIELDS x y z w\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 4294967292\n"
                   "WIDTH 1\nDATA ascii\n1 2 3 4\n",
                   "header declares 1 points of 4294967295 values (COUNT) but the data holds only 8 bytes");
}

TEST(ResourceLimits, OffVertexCount) {
    expect_refused(Target::off, "OFF\n" + k_count + " 1 0\n0 0 0\n",
                   "OFF header declares " + k_count + " vertices");
}

/// A valid pool image with one point, then `edit` applied to its section table, checksums repaired.
std::string pool_with(const std::function<void(prt::pool::SectionEntry&)>& edit,
                      prt::pool::SectionType which) {
    namespace pool = prt::pool;
    pool::PoolWriter writer;
    pool::ModelInfo info{};
    info.point_count = 1;
    writer.add_array(pool::SectionType::model_info, std::vector<pool::ModelInfo>{info});
    writer.add_array(pool::SectionType::positions, std::vector<pool::Float3>{{0.f, 0.f, 0.f}});
    std::vector<std::byte> image = writer.serialize();
    pool::PoolHeader h;
    std::memcpy(&h, image.data(), sizeof h);
    auto* table = reinterpret_cast<pool::SectionEntry*>(image.data() + h.table_offset);
    for (std::uint32_t i = 0; i < h.section_count; ++i)
        if (table[i].type == static_cast<std::uint32_t>(which)) edit(table[i]);
    h.table_checksum =
        pool::checksum({image.data() + h.table_offset, h.section_count * sizeof(pool::SectionEntry)});
    std::memcpy(image.data(), &h, sizeof h);
    h.header_checksum = pool::checksum({image.data(), offsetof(pool::PoolHeader, header_checksum)});
    std::memcpy(image.data(), &h, sizeof h);
    return {reinterpret_cast<const char*>(image.data()), image.size()};
}

TEST(ResourceLimits, PoolSectionClaimingTenToTheFifteenPoints) {
    const std::string bytes = pool_with(
        [](prt::pool::SectionEntry& e) {
            e.count = k_claim;
            e.size = k_claim * 12;
        },
        prt::pool::SectionType::positions);
    expect_refused(Target::pool, bytes, "section positions: payload");
    expect_refused(Target::pool, bytes, "out of bounds");

    // The same through the file reader (memory-mapped), as every tool opens a pool.
    const auto path = prt::fuzz::scratch_dir() / "claim.pool";
    std::ofstream(path, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    g_largest = 0;
    g_armed = true;
    std::string message;
    try {
        (void)prt::pool::PoolFile::open(path);
    } catch (const prt::Error& e) {
        message = e.what();
    }
    g_armed = false;
    EXPECT_NE(message.find(path.string() + ": section positions: payload"), std::string::npos) << message;
    EXPECT_LT(g_largest.load(), k_allocation_limit);
}

TEST(ResourceLimits, PoolCountTimesElementSizeOverflow) {
    // count x element_size wraps around 64 bits to the real payload size: refused by the
    // overflow-free comparison, not trusted.
    expect_refused(Target::pool,
                   pool_with(
                       [](prt::pool::SectionEntry& e) {
                           e.count = (1ull << 62) + 1;
                           e.element_size = 12;
                       },
                       prt::pool::SectionType::positions),
                   "disagrees with size 12");
}

TEST(ResourceLimits, PoolModelInfoClaimingTenToTheFifteenPoints) {
    namespace pool = prt::pool;
    pool::PoolWriter writer;
    pool::ModelInfo info{};
    info.point_count = k_claim;
    writer.add_array(pool::SectionType::model_info, std::vector<pool::ModelInfo>{info});
    writer.add_array(pool::SectionType::positions, std::vector<pool::Float3>{{0.f, 0.f, 0.f}});
    const std::vector<std::byte> image = writer.serialize();
    expect_refused(Target::pool, {reinterpret_cast<const char*>(image.data()), image.size()},
                   "section positions: 1 elements but model_info says " + k_count + " points");
}

TEST(ResourceLimits, PoolSectionCountLimit) {
    std::string bytes = pool_with([](prt::pool::SectionEntry&) {}, prt::pool::SectionType::positions);
    prt::pool::PoolHeader h;
    std::memcpy(&h, bytes.data(), sizeof h);
    h.section_count = 1u << 30;
    std::memcpy(bytes.data(), &h, sizeof h);
    h.header_checksum = prt::pool::checksum(
        {reinterpret_cast<const std::byte*>(bytes.data()), offsetof(prt::pool::PoolHeader, header_checksum)});
    std::memcpy(bytes.data(), &h, sizeof h);
    expect_refused(Target::pool, bytes, "1073741824 sections exceeds the limit of 4096");
}

TEST(ResourceLimits, TheAllocationCounterSeesALargeRequest) {
    // The instrument itself: a reader that did allocate for its claim would be caught.
    g_largest = 0;
    g_armed = true;
    std::vector<char> big(k_allocation_limit + 1);
    g_armed = false;
    EXPECT_GE(g_largest.load(), k_allocation_limit + 1);
    EXPECT_EQ(big.size(), k_allocation_limit + 1);
}

}  // namespace

// ---- Bezier patch files (.bpt and Newell): counts up to pool::k_max_patches are legal, so a
// short file claiming that many must not reserve storage for them.

/// One flat bicubic patch's 16 control point lines.
std::string flat_points(char separator) {
    std::string s;
    for (int k = 0; k < 16; ++k)
        s += std::to_string(k % 4) + separator + std::to_string(k / 4) + separator + "0\n";
    return s;
}

TEST(ResourceLimits, PatchBptCountAtTheLimit) {
    const std::string n = std::to_string(prt::pool::k_max_patches);
    expect_refused(Target::patches, n + "\n3 3\n" + flat_points(' '),
                   "unexpected end of file after 1 of the " + n + " patches the header announces");
}

TEST(ResourceLimits, PatchBptCountTenToTheFifteen) {
    expect_refused(
        Target::patches, k_count + "\n3 3\n" + flat_points(' '),
        "the patch count " + k_count + " exceeds the limit of " + std::to_string(prt::pool::k_max_patches));
}

TEST(ResourceLimits, PatchNewellCountsAtTheLimit) {
    // The patch count at its limit: one index line; then, for a one-patch file, the vertex count
    // at its limit (16 per patch) with one vertex line.
    const std::string n = std::to_string(prt::pool::k_max_patches);
    std::string indices;
    for (int k = 1; k <= 16; ++k) indices += std::to_string(k) + (k < 16 ? "," : "\n");
    expect_refused(Target::patches, n + "\n" + indices,
                   "unexpected end of file after 1 of the " + n + " patches the header announces");
    const std::string v = std::to_string(std::uint64_t(prt::pool::k_max_patches) * 16);
    expect_refused(Target::patches, "1\n" + indices + v + "\n0,0,0\n",
                   "unexpected end of file after 1 of the " + v + " vertices the header announces");
}
