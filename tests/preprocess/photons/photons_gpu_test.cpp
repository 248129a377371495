// prt-photons on the GPU against the CPU (label gpu; skips where no CUDA device is usable): the
// same photons through the same core, so the power accounting agrees within rounding and the
// deposited power within sampling error.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "gi_test_util.h"
#include "photons.h"
#include "prt/cuda/photons_cuda.h"

using namespace prt;

namespace {

/// A glass ball over a floor lit by `lights` (a scene's "lights" array), shot on both backends.
void deposits_match_the_cpu(const std::string& lights) {
    test::TestModel floor =
        test::make_model(test::rect_points({-2, 0, -2}, {4, 0, 0}, {0, 0, 4}, {0, 1, 0}, 300), {0, 0, 0});
    test::TestModel ball = test::make_model(test::sphere_points({0, 0.8, 0}, 0.4, 40000), {0, 0.8, 0});
    const rt::RenderScene rs = test::load_gi_scene(R"({"lights": )" + lights + R"(,
        "materials": [{"name": "floor"},
                      {"name": "glass", "refractive_index": 1.5, "transmissivity": 0.9, "reflectivity": 0.1,
                       "diffuse_reflectance": 0}],
        "models": [{"name": "floor", "pool": "a.pool", "material": "floor"},
                   {"name": "ball", "pool": "b.pool", "material": "glass"}]})",
                                                   {test::make_pool(floor), test::make_pool(ball)});
    photons::ShootOptions o;
    o.params.face_res = 192;
    o.params.per_pixel = 4;
    o.backend = "cpu";
    const photons::ShootResult cpu = photons::shoot_photons(rs.view(), o);
    o.backend = "cuda";
    const photons::ShootResult gpu = photons::shoot_photons(rs.view(), o);
    EXPECT_EQ(gpu.tally.photons, cpu.tally.photons);
    for (int a = 0; a < 3; ++a) {
        EXPECT_NEAR(gpu.tally.emitted[a], cpu.tally.emitted[a], 1e-4 * cpu.tally.emitted[a]);
        const double sum = gpu.tally.direct[a] + gpu.tally.deposited[a] + gpu.tally.absorbed[a] +
                           gpu.tally.escaped[a] + gpu.tally.truncated[a];
        EXPECT_NEAR(sum, gpu.tally.emitted[a], 1e-4 * gpu.tally.emitted[a]);
        EXPECT_NEAR(gpu.tally.deposited[a], cpu.tally.deposited[a], 0.03 * cpu.tally.deposited[a]);
    }
    ASSERT_GT(cpu.tally.deposits, 1000u);
    EXPECT_NEAR(double(gpu.tally.deposits), double(cpu.tally.deposits), 0.03 * cpu.tally.deposits);
    EXPECT_EQ(gpu.deposits.size(), gpu.tally.deposits);
    double cpu_flux = 0, gpu_flux = 0;
    for (const auto& d : cpu.deposits) cpu_flux += d.flux[1];
    for (const auto& d : gpu.deposits) gpu_flux += d.flux[1];
    EXPECT_NEAR(gpu_flux, cpu_flux, 0.03 * cpu_flux);
}

}  // namespace

TEST(PhotonsGpu, DepositsMatchTheCpu) {
    std::string why;
    if (!cuda::photons_device_available(&why)) GTEST_SKIP() << "no CUDA device: " << why;
    deposits_match_the_cpu(R"([{"type": "point", "position": [0.3, 2, 0]}])");
}

TEST(PhotonsGpu, AreaLightDepositsMatchTheCpu) {
    // Issue 20: area lights emit through the same core on both backends.
    std::string why;
    if (!cuda::photons_device_available(&why)) GTEST_SKIP() << "no CUDA device: " << why;
    deposits_match_the_cpu(
        R"([{"type": "area", "corner": [0.1, 2, -0.2], "edge_u": [0.4, 0, 0], "edge_v": [0, 0, 0.4]}])");
}
