// Test fixture for streamed bricks (brick_stream_test.cpp on the CPU, brick_stream_gpu_test.cpp on
// CUDA): a bricked pool of a sphere built in memory (bricks_test_data.h), close views of it, the
// budget's terms redone from the brick table, corrupted copies, rendering until converged.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "bricks_test_data.h"
#include "prt/formats/brick_sections.h"
#include "prt/runtime/backend.h"
#include "prt/runtime/brick_stream.h"
#include "prt/runtime/render_scene.h"

namespace prt::test {

constexpr std::uint32_t k_size = 64;

/// A bricked pool (bricks only, at most 2000 splats a brick) of a 40k-point sphere of radius 2 about
/// (10, -3, 0), written once for all tests.
class BrickStreamFixture : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        s_dir = std::filesystem::temp_directory_path() / ("prt_brick_stream_" + std::to_string(::getpid()));
        std::filesystem::create_directories(s_dir);
        const pool::PoolFile octree = pool::PoolFile::from_bytes(octree_pool_bytes(40000, 16), "octree");
        s_bytes = bricked_bytes(octree, 2000, nullptr, false);
        s_pool = write("sphere.pool", s_bytes);
    }
    static void TearDownTestSuite() { std::filesystem::remove_all(s_dir); }

    static std::filesystem::path write(const char* name, const std::vector<std::byte>& bytes) {
        std::ofstream out(s_dir / name, std::ios::binary);
        out.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
        return s_dir / name;
    }

    /// A close view of the sphere from direction `angle` (radians about +y): a few of its bricks.
    static void close_view(rt::RenderScene& rs, double angle) {
        scene::Camera& c = rs.scene().camera;
        const double cx = 10.0, cy = -3.0, cz = 0.0;
        c.position = {cx + 3.2 * std::sin(angle), cy + 0.4, cz + 3.2 * std::cos(angle)};
        c.look_at = {cx + 2.0 * std::sin(angle), cy, cz + 2.0 * std::cos(angle)};
        c.up = {0, 1, 0};
        c.fov_y_degrees = 30;
        c.width = c.height = k_size;
    }

    /// The scene's frame, rays stopping at level-of-detail discs `lod_pixels` wide (0: never).
    static rt::FrameRequest request(const rt::RenderScene& rs, float lod_pixels = 0.0f) {
        rt::FrameRequest r{.camera = rs.camera(), .params = rs.params(), .width = k_size, .height = k_size};
        r.params.lod_pixels = lod_pixels;
        return r;
    }

    /// The in-core image at `angle` (RenderScene loads and checks every brick, as without streaming);
    /// a negative angle: the default view, the whole sphere.
    static rt::Image in_core(double angle, rt::FrameStats* stats = nullptr, const std::string& kind = "cpu",
                             float lod_pixels = 0.0f) {
        rt::RenderScene rs = rt::RenderScene::from_pool(s_pool);
        if (angle >= 0) close_view(rs, angle);
        auto backend = rt::make_backend(kind);
        backend->set_scene(rs.view());
        rt::Image img;
        const rt::FrameStats s = backend->render(request(rs, lod_pixels), img);
        if (stats) *stats = s;
        return img;
    }

    static rt::RenderScene deferred() {
        rt::LoadOptions lo;
        lo.defer_bricks = true;
        return rt::RenderScene::from_pool(s_pool, lo);
    }

    /// The budget's terms, redone from the brick table: the always-resident bytes (top tree,
    /// table, LOD discs and prefixes, four per-brick tables), the largest brick's block and all blocks (a
    /// block: the payload and its leaf bounds, each rounded up to 64 bytes).
    struct Terms {
        std::uint64_t fixed = 0, largest = 0, all = 0;
        std::uint32_t bricks = 0;
        /// LOD prefixes: all of them (16 bytes a node), the largest one's block (its node count in a
        /// word, then 16 bytes a node, rounded up to 64) and the two per-brick tables of streamed
        /// prefixes.
        std::uint64_t prefixes = 0, largest_prefix = 0, prefix_tables = 0;
        /// The least budget: prefixes streamed, the largest brick's and prefix's blocks.
        std::uint64_t minimum() const { return fixed - prefixes + prefix_tables + largest + largest_prefix; }
    };
    static Terms budget_terms() {
        const pool::PoolFile pf = pool::PoolFile::from_bytes(s_bytes, "sphere");
        const pool::BrickSections s = pool::validate_bricks(pf);
        Terms t;
        for (const pool::BrickEntry& e : s.table) {
            const std::uint64_t block =
                (e.size + 63) / 64 * 64 + (e.leaf_count * sizeof(core::BrickLeafBounds) + 63) / 64 * 64;
            t.largest = std::max(t.largest, block);
            t.all += block;
        }
        t.bricks = s.info.brick_count;
        t.fixed = s.top_nodes.size_bytes() + s.table.size_bytes() + s.lod.size_bytes() +
                  s.lod_table.size_bytes() + s.lod_nodes.size_bytes() + s.lod_discs.size_bytes() +
                  std::uint64_t{t.bricks} * (sizeof(void*) + 12);
        t.prefixes = s.lod_nodes.size() * 16;
        for (const pool::BrickLod& l : s.lod_table)
            t.largest_prefix =
                std::max<std::uint64_t>(t.largest_prefix, (4 + l.node_count * 16ull + 63) / 64 * 64);
        t.prefix_tables = s.lod_table.empty() ? 0 : std::uint64_t{t.bricks} * 8;
        return t;
    }

    /// The pool's bytes with the last byte of every brick payload flipped (the index untouched).
    static std::vector<std::byte> corrupt_every_brick(const pool::PoolFile& pf,
                                                      const pool::BrickSections& s) {
        std::vector<std::byte> bytes(pf.file_bytes().begin(), pf.file_bytes().end());
        for (std::uint32_t b = 0; b < s.info.brick_count; ++b) {
            const auto payload = s.payload(b);
            const std::size_t at = static_cast<std::size_t>(payload.data() - pf.file_bytes().data());
            bytes.at(at + payload.size() - 1) ^= std::byte{0x5a};
        }
        return bytes;
    }

    /// Streams `bad` (every brick corrupted, the close view) on `backend` under half the bricks and
    /// expects the first frame's uploads to stop with one error naming the pool, a brick and the
    /// checksum.
    static void expect_corrupted_brick_refused(const std::filesystem::path& bad, rt::Backend& backend) {
        rt::LoadOptions lo;
        lo.defer_bricks = true;
        rt::RenderScene rs = rt::RenderScene::from_pool(bad, lo);
        close_view(rs, 0.3);
        const Terms t = budget_terms();
        rt::BrickStream stream(rs, backend, rt::StreamOptions{.budget = t.fixed + t.all / 2});
        rt::Image img;
        try {
            stream.after_frame(backend.render(request(rs), img));
            ADD_FAILURE() << "a corrupted brick was uploaded";
        } catch (const Error& e) {
            const std::string what = e.what();
            EXPECT_NE(what.find(bad.filename().string()), std::string::npos) << what;
            EXPECT_NE(what.find("brick "), std::string::npos) << what;
            EXPECT_NE(what.find("checksum"), std::string::npos) << what;
        }
    }

    static inline std::filesystem::path s_dir, s_pool;
    static inline std::vector<std::byte> s_bytes;
};

/// Colour channels (RGB of every pixel) of two same-size images differing by more than `tolerance`.
inline std::size_t channels_differing(const rt::Image& x, const rt::Image& y, int tolerance) {
    std::size_t differ = 0;
    for (std::size_t i = 0; i < x.rgba8.size(); ++i)
        for (int ch = 0; ch < 3; ++ch) {
            const int a = int((x.rgba8[i] >> (8 * ch)) & 255u), b = int((y.rgba8[i] >> (8 * ch)) & 255u);
            differ += std::abs(a - b) > tolerance;
        }
    return differ;
}

/// Renders passes at the scene's camera until one has no fallback (at most `max_passes`).
struct Converged {
    rt::Image image;
    std::uint32_t passes = 0;
    std::uint64_t first_fallbacks = 0;
    std::uint32_t evicted = 0, uploaded = 0, prefix_evictions = 0;
    std::uint32_t prefix_uploads = 0, prefixes_deepened = 0;  ///< coarse parts and whole prefixes
    bool converged = false;
    rt::StreamFrame last;
    rt::FrameStats stats;  ///< the last frame's
};
inline Converged converge(rt::RenderScene& rs, rt::Backend& backend, rt::BrickStream& stream,
                          std::uint32_t max_passes = 400, float lod_pixels = 0.0f) {
    Converged c;
    rt::Refinement refinement;
    for (; c.passes < max_passes;) {
        rt::FrameRequest request{
            .camera = rs.camera(), .params = rs.params(), .width = k_size, .height = k_size};
        request.params.lod_pixels = lod_pixels;
        const rt::FrameStats s = backend.render(request, c.image);
        const rt::StreamFrame f = stream.after_frame(s);
        c.stats = s;
        EXPECT_LE(s.fallbacks, s.rays()) << "fallbacks count rays";
        if (c.passes++ == 0) c.first_fallbacks = s.fallbacks;
        c.evicted += f.evicted;
        c.uploaded += f.uploaded;
        c.prefix_evictions += f.prefixes_evicted;
        c.prefix_uploads += f.prefixes_uploaded;
        c.prefixes_deepened += f.prefixes_deepened;
        c.last = f;
        EXPECT_LE(f.resident_bytes, stream.fixed_bytes() + stream.arena_bytes());
        if (f.converged()) {
            c.converged = true;
            break;
        }
        if (!refinement.more(f)) break;
    }
    return c;
}

}  // namespace prt::test
