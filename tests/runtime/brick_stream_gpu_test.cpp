// Streaming bricks under a memory budget on the CUDA backend (label gpu; issue 17,
// prt/runtime/brick_stream.h, runtime/cuda/src/cuda_brick_storage.cpp): the same checks as
// brick_stream_test.cpp on the GPU: a budget of 40 % of the bricks converges, frame after frame, to
// the CUDA in-core image byte for byte (the same kernels read the same bytes), also with a moving
// camera that forces evictions; the converged image agrees with the CPU's in-core one (fast math:
// isolated pixels may differ); a corrupted brick is refused at upload; the default budget (free
// memory minus a margin) holds this small scene in core; the leaf bounds the GPU derives for streamed
// bricks pass as many leaves as the host's. Skips with a message where no CUDA device
// exists.
#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

#include "brick_stream_fixture.h"
#include "prt/error.h"

namespace prt::test {
namespace {

class BrickStreamGpuTest : public BrickStreamFixture {
protected:
    void SetUp() override {
        const rt::BackendAvailability a = rt::backend_availability();
        if (!a.cuda_device) GTEST_SKIP() << "no CUDA device: " << a.cuda_why;
    }
};

TEST_F(BrickStreamGpuTest, TheDefaultBudgetHoldsASmallSceneInCore) {
    rt::RenderScene rs = deferred();
    close_view(rs, 0.3);
    auto backend = rt::make_backend("cuda");
    const std::uint64_t budget = backend->default_memory_budget();
    EXPECT_GT(budget, 0u);
    rt::BrickStream stream(rs, *backend, rt::StreamOptions{.budget = budget});
    EXPECT_FALSE(stream.streaming());
    rt::Image img;
    const rt::FrameStats s = backend->render(request(rs), img);
    EXPECT_EQ(s.fallbacks, 0u);
    EXPECT_TRUE(img.rgba8 == in_core(0.3, nullptr, "cuda").rgba8);
}

TEST_F(BrickStreamGpuTest, ConvergesToTheInCoreImage) {
    const Terms t = budget_terms();
    rt::FrameStats ref_stats;
    const rt::Image ref = in_core(0.3, &ref_stats, "cuda");
    const rt::Image cpu_ref = in_core(0.3, nullptr, "cpu");
    rt::RenderScene rs = deferred();
    close_view(rs, 0.3);
    const std::uint64_t arena = t.all * 2 / 5 / 64 * 64;
    auto backend = rt::make_backend("cuda");
    rt::BrickStream stream(rs, *backend, rt::StreamOptions{.budget = t.fixed + arena, .upload_per_frame = 1});
    ASSERT_TRUE(stream.streaming());
    EXPECT_EQ(stream.arena_bytes(), arena);
    const Converged c = converge(rs, *backend, stream);
    ASSERT_TRUE(c.converged) << "after " << c.passes << " passes: " << rt::describe(c.last);
    EXPECT_GT(c.passes, 2u);
    EXPECT_GT(c.first_fallbacks, 0u);
    EXPECT_TRUE(c.image.rgba8 == ref.rgba8) << "converged: the CUDA in-core image, byte for byte";
    EXPECT_LT(channels_differing(cpu_ref, c.image, 8), cpu_ref.rgba8.size() / 50)
        << "channels differing from the CPU by more than 8 of 255";
    // The streamed bricks' leaf bounds, derived on the GPU from the payloads (brick_bounds.cu),
    // pass as many leaves unread as the host's bounds of the in-core scene (the same arithmetic;
    // the GPU decodes the splats with fast math, so a leaf at a bound's last bit may differ).
    EXPECT_GT(ref_stats.culled, 0u);
    EXPECT_NEAR(double(c.stats.culled), double(ref_stats.culled), 1e-3 * double(ref_stats.culled) + 2)
        << "leaves passed by their bounds: streamed " << c.stats.culled << ", in core " << ref_stats.culled;
    EXPECT_NEAR(double(c.stats.leaves), double(ref_stats.leaves), 1e-3 * double(ref_stats.leaves) + 2);
}

TEST_F(BrickStreamGpuTest, LevelOfDetailConvergesUnderABudgetThatStallsWithoutIt) {
    // As on the CPU (brick_stream_test.cpp): the whole sphere with rays stopping at discs eight pixels
    // wide converges under 40 % of the bricks to the CUDA in-core image with the same stop, which
    // agrees with the CPU's (the stop level comes from float exponent bits: the same on both).
    const Terms t = budget_terms();
    const rt::Image ref = in_core(-1.0, nullptr, "cuda", 8.0f);
    const rt::Image cpu_ref = in_core(-1.0, nullptr, "cpu", 8.0f);
    rt::RenderScene rs = deferred();
    auto backend = rt::make_backend("cuda");
    rt::BrickStream stream(rs, *backend, rt::StreamOptions{.budget = t.fixed + t.all * 2 / 5});
    const Converged c = converge(rs, *backend, stream, 50, 8.0f);
    ASSERT_TRUE(c.converged) << "after " << c.passes << " passes: " << rt::describe(c.last);
    EXPECT_GT(c.uploaded, 0u);
    EXPECT_LT(c.uploaded, t.bricks / 2);
    EXPECT_TRUE(c.image.rgba8 == ref.rgba8) << "converged: the CUDA in-core image, byte for byte";
    EXPECT_LT(channels_differing(cpu_ref, c.image, 8), cpu_ref.rgba8.size() / 50)
        << "channels differing from the CPU by more than 8 of 255";
}

TEST_F(BrickStreamGpuTest, AMovingCameraEvictsAndStillConverges) {
    const Terms t = budget_terms();
    rt::RenderScene rs = deferred();
    auto backend = rt::make_backend("cuda");
    rt::BrickStream stream(rs, *backend, rt::StreamOptions{.budget = t.fixed + t.all * 2 / 5});
    ASSERT_TRUE(stream.streaming());
    std::uint32_t evicted = 0;
    for (int view = 0; view < 4; ++view) {
        const double angle = 0.3 + 1.6 * view;
        close_view(rs, angle);
        const Converged c = converge(rs, *backend, stream);
        ASSERT_TRUE(c.converged) << "view " << view << ": " << rt::describe(c.last);
        EXPECT_TRUE(c.image.rgba8 == in_core(angle, nullptr, "cuda").rgba8) << "view " << view;
        evicted += c.evicted;
    }
    EXPECT_GT(evicted, 0u);
}

TEST_F(BrickStreamGpuTest, ACorruptedBrickIsRefusedAtUpload) {
    const pool::PoolFile pf = pool::PoolFile::from_bytes(s_bytes, "sphere");
    const std::filesystem::path bad =
        write("corrupt.pool", corrupt_every_brick(pf, pool::validate_bricks(pf)));
    auto backend = rt::make_backend("cuda");
    expect_corrupted_brick_refused(bad, *backend);
}

}  // namespace
}  // namespace prt::test
