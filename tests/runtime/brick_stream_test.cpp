// Streaming bricks under a memory budget (issue 17, prt/runtime/brick_stream.h) on the CPU backend:
// a budget of a few bricks converges, frame after frame, to the in-core image byte for byte (also
// with a moving camera that forces evictions); a budget below the always-resident part is refused in
// one line with the minimum; a corrupted brick is refused when uploaded, naming the pool and brick;
// sizes parse with K/M/G suffixes; fallbacks count rays, not brick visits. The references are the
// in-core renders (every brick loaded and checked, RenderScene without defer_bricks) and, for the
// arena and the minimum, the budget arithmetic redone from the brick table.
#include "prt/runtime/brick_stream.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "brick_stream_fixture.h"
#include "prt/core/render.h"
#include "prt/cpu/cpu_backend.h"
#include "prt/error.h"
#include "prt/runtime/image.h"
#include "prt/tool_util.h"
#include "tool_run.h"

namespace prt::test {
namespace {

using BrickStreamTest = BrickStreamFixture;

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
    EXPECT_EQ(stream.minimum_bytes(), t.minimum()) << "prefixes streamed, the least budget";
    EXPECT_EQ(stream.fixed_bytes(), t.fixed) << "the prefixes fit: resident";
    const Converged c = converge(rs, *backend, stream);
    ASSERT_TRUE(c.converged) << "after " << c.passes << " passes: " << rt::describe(c.last) << ", needed "
                             << c.last.needed;
    EXPECT_GT(c.passes, 2u) << "one brick a frame: refinement takes frames";
    EXPECT_GT(c.first_fallbacks, 0u) << "nothing resident at first: rays use LOD discs";
    EXPECT_TRUE(c.image.rgba8 == ref.rgba8) << "converged: the in-core image, byte for byte";
    std::printf("  converged in %u passes, %u uploads\n", c.passes, c.uploaded);
}

/// A frame whose time is spent uploads one brick (not the many its rays asked for) and leaves the
/// rest to the next frames; frames with time left upload them all.
TEST_F(BrickStreamTest, AFrameOutOfTimeUploadsOneBrickAndTheNextFramesTheRest) {
    rt::FrameStats ref_stats;
    const rt::Image ref = in_core(0.3, &ref_stats);
    const Terms t = budget_terms();
    rt::RenderScene rs = deferred();
    close_view(rs, 0.3);
    auto backend = cpu::make_cpu_backend(2);
    rt::StreamOptions options{.budget = t.fixed + t.all * 2 / 5 / 64 * 64, .frame_seconds = 1e-9};
    rt::BrickStream stream(rs, *backend, options);
    ASSERT_TRUE(stream.streaming());
    rt::Image img;
    rt::FrameStats s = backend->render(request(rs), img);
    s.seconds = 0;  // (a quarter of the render's time is left to streaming: none here)
    const rt::StreamFrame first = stream.after_frame(s);
    ASSERT_GT(first.needed, 3u) << "the test wants a view that asks for several bricks";
    EXPECT_EQ(first.uploaded, 1u);
    EXPECT_TRUE(first.timed_out);
    EXPECT_EQ(first.missing + 1, first.needed) << rt::describe(first);
    // With a render of 10 s (a quarter of it left to streaming), the next frames upload the rest:
    // the in-core image.
    std::uint32_t passes = 1;
    for (rt::StreamFrame f = first; !f.converged() && passes < 50; ++passes) {
        s = backend->render(request(rs), img);
        s.seconds = 10;
        f = stream.after_frame(s);
        EXPECT_FALSE(f.timed_out);
    }
    s = backend->render(request(rs), img);
    EXPECT_EQ(s.fallbacks, 0u) << "after " << passes << " passes";
    EXPECT_TRUE(img.rgba8 == ref.rgba8) << "converged: the in-core image, byte for byte";
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

/// Level of detail: the whole sphere (the default view) needs more bricks than 40 % of them, so it
/// stalls; with rays stopping at discs eight pixels wide it needs a few bricks (those whose prefixes
/// are too coarse for the front of the sphere) and converges to the in-core image with the same
/// stop, byte for byte.
TEST_F(BrickStreamTest, LevelOfDetailConvergesUnderABudgetThatStallsWithoutIt) {
    const Terms t = budget_terms();
    const rt::Image ref = in_core(-1.0, nullptr, "cpu", 8.0f);
    auto backend = cpu::make_cpu_backend(2);
    rt::RenderScene exact = deferred();
    rt::BrickStream exact_stream(exact, *backend, rt::StreamOptions{.budget = t.fixed + t.all * 2 / 5});
    const Converged without = converge(exact, *backend, exact_stream, 50, 0.0f);
    EXPECT_FALSE(without.converged) << "the whole sphere's bricks do not fit";
    rt::RenderScene rs = deferred();
    rt::BrickStream stream(rs, *backend, rt::StreamOptions{.budget = t.fixed + t.all * 2 / 5});
    const Converged c = converge(rs, *backend, stream, 50, 8.0f);
    ASSERT_TRUE(c.converged) << "after " << c.passes << " passes: " << rt::describe(c.last) << ", needed "
                             << c.last.needed;
    EXPECT_TRUE(c.image.rgba8 == ref.rgba8) << "converged: the in-core image with the same stop";
    EXPECT_LT(c.uploaded, without.last.needed) << "the far parts need no brick";
    EXPECT_GT(c.uploaded, 0u) << "the near parts do";
    std::printf("  without LOD: %u bricks needed; with: converged in %u passes, %u uploads of %u bricks\n",
                without.last.needed, c.passes, c.uploaded, t.bricks);
}

/// Streamed LOD prefixes: under a budget that cannot hold every prefix with the top tree, the
/// prefixes stream into the arena with the payloads (a ray reaching a brick whose prefix is missing
/// meets its top-node disc and asks for the prefix's coarse part, then, if its stop lies deeper, for
/// the whole prefix, then for the payload); the view converges to the in-core image with the same
/// stop, byte for byte, the far view with coarse parts where its rays stop in them, and turning the
/// camera evicts prefixes (with their payloads) least recently used first. They stream by default
/// where they would take more than half of the arena and prefixes, else on request
/// (StreamOptions::stream_prefixes: this fixture's views need an arena larger than its prefixes).
TEST_F(BrickStreamTest, LodPrefixesStreamWhenTheBudgetCannotHoldThem) {
    const Terms t = budget_terms();
    ASSERT_GT(t.prefixes, 0u) << "the fixture's pool has LOD prefixes";
    auto backend = cpu::make_cpu_backend(2);
    {  // the default: resident when they take at most half of the arena and prefixes
        rt::RenderScene small = deferred(), ample = deferred();
        const rt::BrickStream streams(small, *backend,
                                      rt::StreamOptions{.budget = t.fixed + t.largest + t.prefixes / 2});
        EXPECT_EQ(streams.fixed_bytes(), t.fixed - t.prefixes + t.prefix_tables)
            << "more than half: streamed";
        const rt::BrickStream resident(ample, *backend,
                                       rt::StreamOptions{.budget = t.fixed + t.largest + t.prefixes});
        EXPECT_EQ(resident.fixed_bytes(), t.fixed) << "half: resident";
    }
    const std::uint64_t budget = t.minimum() + t.all * 3 / 10;
    rt::RenderScene rs = deferred();
    rt::BrickStream stream(
        rs, *backend, rt::StreamOptions{.budget = budget, .upload_per_frame = 1, .stream_prefixes = true});
    ASSERT_TRUE(stream.streaming());
    EXPECT_EQ(stream.minimum_bytes(), t.minimum());
    EXPECT_EQ(stream.fixed_bytes(), t.fixed - t.prefixes + t.prefix_tables) << "no prefix resident";
    EXPECT_EQ(stream.arena_bytes(), t.largest + (budget - stream.fixed_bytes() - t.largest) / 64 * 64)
        << "the arena: the rest of the budget, payloads and prefixes alike";
    std::uint32_t prefix_evictions = 0, deepened = 0;
    for (const double angle : {-1.0, 0.3, 1.9}) {
        SCOPED_TRACE(::testing::Message() << "view " << angle);
        if (angle >= 0) close_view(rs, angle);
        const Converged c = converge(rs, *backend, stream, 800, 4.0f);  // one upload a pass
        ASSERT_TRUE(c.converged) << "after " << c.passes << " passes: " << rt::describe(c.last) << ", needed "
                                 << c.last.needed;
        EXPECT_TRUE(c.last.streamed_prefixes);
        EXPECT_GT(c.first_fallbacks, 0u);
        EXPECT_TRUE(c.image.rgba8 == in_core(angle, nullptr, "cpu", 4.0f).rgba8)
            << "converged: the in-core image with the same stop";
        EXPECT_GT(c.last.resident_prefixes, 0u);
        if (angle < 0)
            EXPECT_LT(c.prefixes_deepened, c.prefix_uploads - c.prefixes_deepened)
                << "the whole sphere: some bricks' rays all stop in their prefix's coarse part";
        prefix_evictions += c.prefix_evictions;
        deepened += c.prefixes_deepened;
        std::printf(
            "  view %.1f: converged in %u passes, %u uploads, %u prefixes resident (%u uploads, %u "
            "deepened), %u prefix evictions\n",
            angle, c.passes, c.uploaded, c.last.resident_prefixes, c.prefix_uploads, c.prefixes_deepened,
            c.prefix_evictions);
    }
    EXPECT_GT(prefix_evictions, 0u) << "three views under a quarter of the bricks evict prefixes";
    EXPECT_GT(deepened, 0u) << "the close views' rays go below the coarse parts";
}

/// Level of detail through bounces (render.h lod_cone): a ray leaving a hit starts with the footprint
/// its camera ray had there, so shadow and reflected rays ask for no finer bricks than the camera
/// rays they come from. The whole
/// sphere at discs eight pixels wide: its shadow rays (toward a light in front) and mirror rays
/// (away from a convex surface) need no brick beyond the camera rays' own; starting with no
/// footprint they needed every brick they left. Converged, the image is the in-core one.
TEST_F(BrickStreamTest, RaysLeavingAHitNeedNoFinerBricksThanTheirCameraRays) {
    const Terms t = budget_terms();
    auto backend = cpu::make_cpu_backend(2);
    rt::LoadOptions lo;
    lo.defer_bricks = true;
    // Half the bricks: streamed, so each frame counts the bricks its rays reached.
    const rt::StreamOptions ample{.budget = t.fixed + t.all / 2};
    auto needed = [&](bool bounces, rt::Image* image) {
        scene::Scene sc = rt::RenderScene::from_pool(s_pool).scene();
        sc.materials.at(0).reflectivity = bounces ? 0.5f : 0.0f;
        rt::RenderScene rs = rt::RenderScene::load(sc, s_pool, lo);
        rs.params().shadows = bounces ? 1 : 0;
        rt::BrickStream stream(rs, *backend, ample);
        EXPECT_TRUE(stream.streaming());
        const Converged c = converge(rs, *backend, stream, 50, 8.0f);
        EXPECT_TRUE(c.converged) << rt::describe(c.last);
        if (bounces) {
            EXPECT_GT(c.stats.shadow, 0u);
            EXPECT_GT(c.stats.secondary, 0u);
        }
        if (image) *image = c.image;
        return c.last.needed;
    };
    const std::uint32_t camera = needed(false, nullptr);
    rt::Image img;
    const std::uint32_t all = needed(true, &img);
    EXPECT_GT(camera, 0u) << "the front of the sphere is finer than the prefixes";
    EXPECT_LE(all, camera + camera / 10) << "shadow and mirror rays asked for finer bricks than their hits";
    std::printf("  bricks needed: camera rays %u, with shadow and mirror rays %u (of %u)\n", camera, all,
                t.bricks);
    // In core, the same image.
    scene::Scene sc = rt::RenderScene::from_pool(s_pool).scene();
    sc.materials.at(0).reflectivity = 0.5f;
    rt::RenderScene rs = rt::RenderScene::load(sc, s_pool);
    auto in_core_backend = cpu::make_cpu_backend(2);
    in_core_backend->set_scene(rs.view());
    rt::Image ref;
    in_core_backend->render(request(rs, 8.0f), ref);
    EXPECT_TRUE(img.rgba8 == ref.rgba8) << "converged: the in-core image with the same stops";
}

/// Below the always-resident part (LOD prefixes streamed) and the largest brick and prefix: one
/// line with the minimum.
TEST_F(BrickStreamTest, ATooSmallBudgetIsRefusedWithTheMinimum) {
    const Terms t = budget_terms();
    for (const std::uint64_t budget : {std::uint64_t{1}, t.minimum() - 1}) {
        rt::RenderScene rs = deferred();
        auto backend = cpu::make_cpu_backend(2);
        try {
            rt::BrickStream stream(rs, *backend, rt::StreamOptions{.budget = budget});
            ADD_FAILURE() << "budget " << budget << " accepted";
        } catch (const Error& e) {
            const std::string what = e.what();
            EXPECT_EQ(what.find('\n'), std::string::npos) << what;
            EXPECT_NE(what.find("too small"), std::string::npos) << what;
            EXPECT_NE(what.find(tool::format_bytes(t.minimum())), std::string::npos) << what;
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
    auto backend = cpu::make_cpu_backend(2);
    expect_corrupted_brick_refused(bad, *backend);
    rt::LoadOptions lo;
    lo.defer_bricks = true;
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

/// prt-bench under a budget: it refines before timing, reports the streaming numbers (JSON), and
/// the timed frames use no coarse level.
TEST_F(BrickStreamTest, PrtBenchReportsStreaming) {
    const auto json = s_dir / "bench.json";
    const ToolRun r =
        run_tool("prt-bench",
                 s_pool.string() +
                     " --backend cpu --gpu-budget 1200K --frames 2 --warmup 1 --scenarios primary "
                     "--width 48 --height 48 --eye 12.0,-2.6,2.6 --look-at 11.0,-3,1.7 --fov 30 "
                     "--json " +
                     json.string(),
                 s_dir);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.out.find("streaming"), std::string::npos) << r.out;
    const nlohmann::json j = nlohmann::json::parse(slurp(json));
    EXPECT_TRUE(j["streaming"]["streamed"].get<bool>());
    EXPECT_EQ(j["streaming"]["budget_bytes"].get<std::uint64_t>(), 1200u * 1024);
    const nlohmann::json& sc = j["scenarios"][0];
    EXPECT_TRUE(sc["streaming"]["converged"].get<bool>()) << sc.dump();
    EXPECT_GT(sc["streaming"]["bricks_uploaded"].get<std::uint64_t>(), 0u);
    EXPECT_EQ(sc["brick_fallbacks"].get<std::uint64_t>(), 0u) << "timed after converging";
}

/// FrameStats::fallbacks counts rays, not brick visits: with nothing resident and primary rays only,
/// it equals the primary rays whose walk fell back at least once, counted here ray by ray with the
/// core's walk (which also counts the visits: more than the rays).
TEST_F(BrickStreamTest, FallbacksCountRaysNotBrickVisits) {
    const Terms t = budget_terms();
    rt::RenderScene rs = deferred();
    rs.params().shadows = 0;
    rs.params().reflections = 0;
    rs.params().refractions = 0;
    auto backend = cpu::make_cpu_backend(2);
    rt::BrickStream stream(rs, *backend, rt::StreamOptions{.budget = t.fixed + t.all / 4});
    ASSERT_TRUE(stream.streaming());
    rt::Image img;
    const rt::FrameStats fs = backend->render(request(rs), img);
    ASSERT_EQ(fs.shadow + fs.secondary, 0u);
    const core::SceneView view = rs.view();
    core::BrickView bricks = view.models[0].bricks;  // nothing resident yet; no flags touched here
    bricks.requests = nullptr;
    bricks.used = nullptr;
    const core::PinholeCamera cam = rs.camera();
    const core::BlendOptions blend{rs.params().blend_window, rs.params().deep_blending != 0};
    std::uint64_t rays = 0, visits = 0;
    for (std::uint32_t y = 0; y < k_size; ++y)
        for (std::uint32_t x = 0; x < k_size; ++x) {
            const core::Ray r = core::primary_ray(cam, x, y, k_size, k_size);
            core::Vec3 o, d;
            core::to_model_frame(view.models[0], r, o, d);
            core::WalkStats st;
            core::SplatSample h{};
            core::closest_hit_bricks(bricks, o, d, false, r.t_max, blend, rs.params().max_steps, h, st,
                                     rs.params().leaf_culling);
            rays += st.fallbacks > 0;
            visits += st.fallbacks;
        }
    EXPECT_GT(rays, 0u);
    EXPECT_EQ(fs.fallbacks, rays);
    EXPECT_GT(visits, rays) << "some rays pass several bricks' discs: visits would count more";
}

/// What a ray asks streaming for (bricks.h stopped_at_disc, descend_bricked), ray by ray over the
/// whole sphere at discs eight pixels wide: with nothing resident it requests at most one brick, the
/// first missing one on its way, which is one whose payload its in-core walk needs (flags used); and
/// a ray whose in-core walk needs no payload (it stops in prefixes) requests none. So a view asks for
/// part of what its in-core render needs, never for bricks seen through a stand-in disc.
TEST_F(BrickStreamTest, ARayAsksForTheFirstMissingBrickItsInCoreWalkNeeds) {
    const Terms t = budget_terms();
    rt::RenderScene full = rt::RenderScene::from_pool(s_pool);  // every brick resident
    rt::RenderScene rs = deferred();
    auto backend = cpu::make_cpu_backend(2);
    // An arena of a quarter of the bricks and three times the prefixes: the prefixes resident.
    rt::BrickStream stream(rs, *backend, rt::StreamOptions{.budget = t.fixed + t.all / 4 + 3 * t.prefixes});
    ASSERT_TRUE(stream.streaming());
    ASSERT_EQ(stream.fixed_bytes(), t.fixed) << "the prefixes resident";
    const core::SceneView in_core = full.view(), missing = rs.view();  // nothing resident yet
    std::vector<std::uint32_t> used(t.bricks), requested(t.bricks);
    core::BrickView with_all = in_core.models[0].bricks, with_none = missing.models[0].bricks;
    with_all.used = used.data();
    with_all.requests = requested.data();
    with_none.used = used.data();
    with_none.requests = requested.data();
    ASSERT_EQ(with_all.resident, nullptr);
    const core::PinholeCamera cam = full.camera();
    const core::BlendOptions blend{full.params().blend_window, full.params().deep_blending != 0};
    const float spread = 2.0f * core::pixel_angle(cam, k_size);
    std::uint32_t rays_needing = 0, rays_with_several = 0, rays_in_prefixes = 0;
    for (std::uint32_t y = 0; y < k_size; ++y)
        for (std::uint32_t x = 0; x < k_size; ++x) {
            const core::Ray r = core::primary_ray(cam, x, y, k_size, k_size);
            core::Vec3 o, d;
            core::to_model_frame(in_core.models[0], r, o, d);
            const core::LodCone cone{0.0f, spread * in_core.models[0].inv_scale};
            auto walk = [&](const core::BrickView& v) {
                std::fill(used.begin(), used.end(), 0u);
                std::fill(requested.begin(), requested.end(), 0u);
                core::WalkStats st;
                core::SplatSample h{};
                core::closest_hit_bricks(v, o, d, false, r.t_max, blend, full.params().max_steps, h, st,
                                         full.params().leaf_culling, cone);
                return st;
            };
            walk(with_all);
            ASSERT_EQ(std::count(requested.begin(), requested.end(), 1u), 0) << "in core: no request";
            const std::vector<std::uint32_t> needs = used;
            const auto n_needs = std::count(needs.begin(), needs.end(), 1u);
            const core::WalkStats st = walk(with_none);
            ASSERT_EQ(std::count(used.begin(), used.end(), 1u), 0) << "nothing resident: nothing used";
            const auto n_requests = std::count(requested.begin(), requested.end(), 1u);
            ASSERT_EQ(n_requests, n_needs > 0 ? 1 : 0) << "pixel " << x << ", " << y;
            for (std::uint32_t b = 0; b < t.bricks; ++b) {
                if (requested[b] != 0) {
                    ASSERT_EQ(needs[b], 1u) << "pixel " << x << ", " << y << " brick " << b;
                }
            }
            rays_needing += n_needs > 0;
            rays_with_several += n_needs > 1;
            rays_in_prefixes += n_needs == 0 && st.fallbacks == 0 && st.leaves > 0;
        }
    EXPECT_GT(rays_needing, 0u);
    EXPECT_GT(rays_with_several, 0u) << "some rays need several bricks: only the first is asked for";
    std::printf("  rays needing a brick %u (several %u), staying in prefixes %u\n", rays_needing,
                rays_with_several, rays_in_prefixes);
}

/// The window refines frame after frame: under xvfb-run, after 20 frames under a budget the
/// displayed image is the in-core render (within the window test's tolerance: the texture path).
/// The suite's name ends in WindowTest: scripts/asan-tests.sh runs window tests without leak
/// detection (the OpenGL driver's allocations).
using BrickStreamWindowTest = BrickStreamFixture;
TEST_F(BrickStreamWindowTest, TheWindowRefinesToTheInCoreImage) {
#ifndef PRT_TEST_HAVE_WINDOW
    GTEST_SKIP() << "this build has no player window (configured without GLFW)";
#endif
    if (!on_path("xvfb-run"))
        GTEST_SKIP() << "xvfb-run is not installed (Debian: apt-get install xvfb xauth): window test skipped";
    const std::string view =
        " --backend cpu --eye 12.0,-2.6,2.6 --look-at 11.0,-3,1.7 --fov 30 --width 48 --height 48";
    const auto shot = s_dir / "shot.ppm", ref = s_dir / "ref.ppm";
    const ToolRun win =
        run_tool("prt-play",
                 s_pool.string() + view + " --gpu-budget 1200K --upload-per-frame 64K --frames 20 " +
                     "--screenshot " + shot.string(),
                 s_dir, "xvfb-run -a -s '-screen 0 640x480x24'");
    ASSERT_EQ(win.code, 0) << win.err;
    EXPECT_NE(win.err.find("uploaded"), std::string::npos) << win.err;
    const ToolRun head = run_tool("prt-play", s_pool.string() + view + " --out " + ref.string(), s_dir);
    ASSERT_EQ(head.code, 0) << head.err;
    const rt::Image a = rt::read_ppm(shot), b = rt::read_ppm(ref);
    ASSERT_EQ(a.width, b.width);
    ASSERT_EQ(a.height, b.height);
    std::size_t off = 0;
    for (std::size_t i = 0; i < a.rgba8.size(); ++i)
        for (int c = 0; c < 3; ++c)
            off += std::abs(int((a.rgba8[i] >> (8 * c)) & 255u) - int((b.rgba8[i] >> (8 * c)) & 255u)) > 2;
    EXPECT_LE(off, a.rgba8.size() * 3 / 100) << "channels more than 2 levels apart: " << win.err;
}

}  // namespace
}  // namespace prt::test
