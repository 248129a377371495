// Streaming bricks under a memory budget (issue 17, prt/runtime/brick_stream.h) on the CPU backend:
// a budget of a few bricks converges, frame after frame, to the in-core image byte for byte (also
// with a moving camera that forces evictions); a budget below the always-resident part is refused in
// one line with the minimum; a corrupted brick is refused when uploaded, naming the pool and brick;
// sizes parse with K/M/G suffixes; fallbacks count rays, not brick visits. The references are the
// in-core renders (every brick loaded and checked, RenderScene without defer_bricks) and, for the
// arena and the minimum, the budget arithmetic redone from the brick table.
#include "prt/runtime/brick_stream.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "bricks_test_data.h"
#include "prt/cpu/cpu_backend.h"
#include "prt/error.h"
#include "prt/formats/brick_sections.h"
#include "prt/runtime/render_scene.h"
#include "tool_run.h"

namespace prt::test {
namespace {

constexpr std::uint32_t k_size = 64;

/// A bricked pool (bricks only, at most 2000 splats a brick) of a 40k-point sphere of radius 2 about
/// (10, -3, 0), written once for all tests.
class BrickStreamTest : public ::testing::Test {
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

    static rt::FrameRequest request(const rt::RenderScene& rs) {
        return rt::FrameRequest{
            .camera = rs.camera(), .params = rs.params(), .width = k_size, .height = k_size};
    }

    /// The in-core image at `angle` (RenderScene loads and checks every brick, as without streaming).
    static rt::Image in_core(double angle, rt::FrameStats* stats = nullptr) {
        rt::RenderScene rs = rt::RenderScene::from_pool(s_pool);
        close_view(rs, angle);
        auto backend = cpu::make_cpu_backend(2);
        backend->set_scene(rs.view());
        rt::Image img;
        const rt::FrameStats s = backend->render(request(rs), img);
        if (stats) *stats = s;
        return img;
    }

    static rt::RenderScene deferred() {
        rt::LoadOptions lo;
        lo.defer_bricks = true;
        return rt::RenderScene::from_pool(s_pool, lo);
    }

    /// The budget's terms, redone from the brick table: the always-resident bytes (top tree,
    /// table, LOD discs, four per-brick tables), the largest brick's block and all blocks (a block:
    /// the payload and its leaf bounds, each rounded up to 64 bytes).
    struct Terms {
        std::uint64_t fixed = 0, largest = 0, all = 0;
        std::uint32_t bricks = 0;
    };
    static Terms budget_terms() {
        const pool::PoolFile pf = pool::PoolFile::from_bytes(s_bytes, "sphere");
        const pool::BrickSections s = pool::validate_bricks(pf);
        Terms t;
        for (const pool::BrickEntry& e : s.table) {
            const std::uint64_t block =
                (e.size + 63) / 64 * 64 + (e.leaf_count * sizeof(core::LeafBounds) + 63) / 64 * 64;
            t.largest = std::max(t.largest, block);
            t.all += block;
        }
        t.bricks = s.info.brick_count;
        t.fixed = s.top_nodes.size_bytes() + s.table.size_bytes() + s.lod.size_bytes() +
                  std::uint64_t{t.bricks} * (sizeof(void*) + 12);
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

    static inline std::filesystem::path s_dir, s_pool;
    static inline std::vector<std::byte> s_bytes;
};

/// Renders passes at the scene's camera until one has no fallback (at most `max_passes`).
struct Converged {
    rt::Image image;
    std::uint32_t passes = 0;
    std::uint64_t first_fallbacks = 0;
    std::uint32_t evicted = 0, uploaded = 0;
    bool converged = false;
    rt::StreamFrame last;
};
Converged converge(rt::RenderScene& rs, rt::Backend& backend, rt::BrickStream& stream,
                   std::uint32_t max_passes = 400) {
    Converged c;
    for (; c.passes < max_passes;) {
        const rt::FrameStats s = backend.render(
            rt::FrameRequest{.camera = rs.camera(), .params = rs.params(), .width = k_size, .height = k_size},
            c.image);
        const rt::StreamFrame f = stream.after_frame(s);
        EXPECT_LE(s.fallbacks, s.rays()) << "fallbacks count rays";
        if (c.passes++ == 0) c.first_fallbacks = s.fallbacks;
        c.evicted += f.evicted;
        c.uploaded += f.uploaded;
        c.last = f;
        EXPECT_LE(f.resident_bytes, stream.fixed_bytes() + stream.arena_bytes());
        if (f.converged()) {
            c.converged = true;
            break;
        }
        if (f.uploaded == 0) break;
    }
    return c;
}

TEST_F(BrickStreamTest, ParsesSizes) {
    EXPECT_EQ(rt::parse_byte_size("4096", "--gpu-budget"), 4096u);
    EXPECT_EQ(rt::parse_byte_size("512K", "--gpu-budget"), 512u * 1024);
    EXPECT_EQ(rt::parse_byte_size("300M", "--gpu-budget"), 300ull << 20);
    EXPECT_EQ(rt::parse_byte_size("1.5G", "--gpu-budget"), 3ull << 29);
    EXPECT_EQ(rt::parse_byte_size("2gib", "--gpu-budget"), 2ull << 30);
    EXPECT_EQ(rt::parse_byte_size("8MB", "--gpu-budget"), 8ull << 20);
    for (const char* bad : {"", "G", "12Q", "-1M", "1e400", "nan"})
        EXPECT_THROW(rt::parse_byte_size(bad, "--gpu-budget"), Error) << bad;
}

/// A budget that holds everything: in core, the same image as without streaming.
TEST_F(BrickStreamTest, AnAmpleBudgetLoadsInCore) {
    const rt::Image ref = in_core(0.3);
    rt::RenderScene rs = deferred();
    close_view(rs, 0.3);
    auto backend = cpu::make_cpu_backend(2);
    rt::BrickStream stream(rs, *backend, rt::StreamOptions{.budget = 1ull << 30});
    EXPECT_FALSE(stream.streaming());
    rt::Image img;
    const rt::FrameStats s = backend->render(request(rs), img);
    EXPECT_EQ(s.fallbacks, 0u);
    EXPECT_TRUE(stream.after_frame(s).converged());
    EXPECT_EQ(img.rgba8, ref.rgba8);
}

/// A budget of a few bricks (far fewer than the pool's) converges to the in-core image.
TEST_F(BrickStreamTest, ConvergesToTheInCoreImage) {
    rt::FrameStats ref_stats;
    const rt::Image ref = in_core(0.3, &ref_stats);
    const Terms t = budget_terms();
    ASSERT_GT(t.bricks, 100u) << "the test wants many bricks";
    rt::RenderScene rs = deferred();
    close_view(rs, 0.3);
    const std::uint64_t arena = t.all * 2 / 5 / 64 * 64;  // 40 % of the bricks' bytes
    auto backend = cpu::make_cpu_backend(2);
    // At most one brick a frame, so refinement takes several frames.
    rt::BrickStream stream(rs, *backend, rt::StreamOptions{.budget = t.fixed + arena, .upload_per_frame = 1});
    ASSERT_TRUE(stream.streaming());
    EXPECT_EQ(stream.arena_bytes(), arena);
    EXPECT_EQ(stream.brick_count(), t.bricks);
    EXPECT_EQ(stream.minimum_bytes(), t.fixed + t.largest);
    EXPECT_EQ(stream.fixed_bytes(), t.fixed);
    const Converged c = converge(rs, *backend, stream);
    ASSERT_TRUE(c.converged) << "after " << c.passes << " passes: " << rt::describe(c.last) << ", needed "
                             << c.last.needed;
    EXPECT_GT(c.passes, 2u) << "one brick a frame: refinement takes frames";
    EXPECT_GT(c.first_fallbacks, 0u) << "nothing resident at first: rays use LOD discs";
    EXPECT_TRUE(c.image.rgba8 == ref.rgba8) << "converged: the in-core image, byte for byte";
    std::printf("  converged in %u passes, %u uploads\n", c.passes, c.uploaded);
}

/// A moving camera under a budget smaller than the union of its views: bricks are evicted, and
/// every view still converges to its in-core image.
TEST_F(BrickStreamTest, AMovingCameraEvictsAndStillConverges) {
    const Terms t = budget_terms();
    rt::RenderScene rs = deferred();
    auto backend = cpu::make_cpu_backend(2);
    rt::BrickStream stream(rs, *backend, rt::StreamOptions{.budget = t.fixed + t.all * 2 / 5});
    ASSERT_TRUE(stream.streaming());
    std::uint32_t evicted = 0;
    for (int view = 0; view < 4; ++view) {
        const double angle = 0.3 + 1.6 * view;  // four sides of the sphere: few bricks shared
        close_view(rs, angle);
        const Converged c = converge(rs, *backend, stream);
        ASSERT_TRUE(c.converged) << "view " << view << ": " << rt::describe(c.last) << ", needed "
                                 << c.last.needed;
        EXPECT_EQ(c.image.rgba8, in_core(angle).rgba8) << "view " << view;
        evicted += c.evicted;
    }
    EXPECT_GT(evicted, 0u) << "40 % of the bricks cannot hold four sides' bricks";
}

/// A budget that cannot hold the view's bricks: rendering stops refining (nothing can be evicted),
/// and the arena never holds more than its bytes.
TEST_F(BrickStreamTest, ABudgetSmallerThanTheViewStalls) {
    const Terms t = budget_terms();
    rt::RenderScene rs = deferred();  // the default view frames the whole sphere: many bricks
    auto backend = cpu::make_cpu_backend(2);
    rt::BrickStream stream(rs, *backend, rt::StreamOptions{.budget = t.fixed + 2 * t.largest});
    ASSERT_TRUE(stream.streaming());
    rt::Image img;
    rt::StreamFrame f;
    for (int i = 0; i < 4; ++i) f = stream.after_frame(backend->render(request(rs), img));
    EXPECT_FALSE(f.converged());
    EXPECT_TRUE(f.stalled);
    EXPECT_EQ(f.uploaded, 0u);
    EXPECT_GE(f.resident_bricks, 2u) << "two blocks of the largest brick hold at least two bricks";
    EXPECT_GT(f.needed, f.resident_bricks);
}

/// Below the always-resident part and the largest brick: one line with the minimum.
TEST_F(BrickStreamTest, ATooSmallBudgetIsRefusedWithTheMinimum) {
    const Terms t = budget_terms();
    for (const std::uint64_t budget : {std::uint64_t{1}, t.fixed + t.largest - 1}) {
        rt::RenderScene rs = deferred();
        auto backend = cpu::make_cpu_backend(2);
        try {
            rt::BrickStream stream(rs, *backend, rt::StreamOptions{.budget = budget});
            ADD_FAILURE() << "budget " << budget << " accepted";
        } catch (const Error& e) {
            const std::string what = e.what();
            EXPECT_EQ(what.find('\n'), std::string::npos) << what;
            EXPECT_NE(what.find("too small"), std::string::npos) << what;
            EXPECT_NE(what.find(rt::format_bytes(t.fixed + t.largest)), std::string::npos) << what;
        }
    }
}

/// A brick whose payload is corrupted: the pool opens (its index is sound), and the brick is
/// refused when it is uploaded, naming the pool and the brick; in core, at load.
TEST_F(BrickStreamTest, ACorruptedBrickIsRefusedAtUpload) {
    const pool::PoolFile pf = pool::PoolFile::from_bytes(s_bytes, "sphere");
    const pool::BrickSections s = pool::validate_bricks(pf);
    // Every brick of the close view is a candidate: corrupt each payload's last splat byte.
    const std::vector<std::byte> bytes = corrupt_every_brick(pf, s);
    const std::filesystem::path bad = write("corrupt.pool", bytes);
    rt::LoadOptions lo;
    lo.defer_bricks = true;
    rt::RenderScene rs = rt::RenderScene::from_pool(bad, lo);
    close_view(rs, 0.3);
    auto backend = cpu::make_cpu_backend(2);
    const Terms t = budget_terms();
    rt::BrickStream stream(rs, *backend, rt::StreamOptions{.budget = t.fixed + t.all / 2});
    rt::Image img;
    try {
        stream.after_frame(backend->render(request(rs), img));
        ADD_FAILURE() << "a corrupted brick was uploaded";
    } catch (const Error& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find("corrupt.pool"), std::string::npos) << what;
        EXPECT_NE(what.find("brick "), std::string::npos) << what;
        EXPECT_NE(what.find("checksum"), std::string::npos) << what;
    }
    rt::RenderScene all = rt::RenderScene::from_pool(bad, lo);
    EXPECT_THROW(rt::BrickStream(all, *backend, rt::StreamOptions{}), Error) << "in core: refused at load";
}

/// prt-play: --gpu-budget and --converge write the in-core image; a too-small budget and a corrupted
/// brick fail in one line, exit 1, nothing written.
TEST_F(BrickStreamTest, PrtPlayStreamsAndConverges) {
    const std::string view = " --eye 12.0,-2.6,2.6 --look-at 11.0,-3,1.7 --fov 30 --width 48 --height 48";
    const auto in_core_img = s_dir / "in_core.ppm", streamed = s_dir / "streamed.ppm";
    ToolRun r = run_tool(
        "prt-play", s_pool.string() + view + " --backend cpu --quiet --out " + in_core_img.string(), s_dir);
    ASSERT_EQ(r.code, 0) << r.err;
    r = run_tool("prt-play",
                 s_pool.string() + view +
                     " --backend cpu --gpu-budget 1200K --converge --upload-per-frame 1 --out " +
                     streamed.string(),
                 s_dir);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.err.find("streaming "), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("rays fell back"), std::string::npos) << r.err;
    EXPECT_TRUE(slurp(streamed) == slurp(in_core_img)) << r.err;

    const auto none = s_dir / "none.ppm";
    r = run_tool("prt-play", s_pool.string() + view + " --backend cpu --gpu-budget 1K --out " + none.string(),
                 s_dir);
    EXPECT_EQ(r.code, 1);
    expect_one_line(r.err, {"too small", "at least"});
    EXPECT_FALSE(std::filesystem::exists(none));

    const pool::PoolFile pf = pool::PoolFile::from_bytes(s_bytes, "sphere");
    const std::vector<std::byte> bytes = corrupt_every_brick(pf, pool::validate_bricks(pf));
    const auto bad = write("bad.pool", bytes);
    r = run_tool(
        "prt-play",
        bad.string() + view + " --backend cpu --gpu-budget 1200K --converge --quiet --out " + none.string(),
        s_dir);
    EXPECT_EQ(r.code, 1);
    expect_one_line(r.err, {"bad.pool", "brick ", "checksum"});
    EXPECT_FALSE(std::filesystem::exists(none));
}

}  // namespace
}  // namespace prt::test
