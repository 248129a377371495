// prt-bench-cast: rays per second of the public C++ API (prt/pointrt.h, issue 18) on a batch of rays
// read from a file: float32 records of 6 values (origin x y z, direction x y z), as
// scripts/bench-cast.py writes them, so the Python module and the C++ API cast the same rays.
// Prints one line per repeat and the best: "cpp: N rays in S s = R Mrays/s (hits H)".
//
//     prt-bench-cast POOL RAYS.f32 [--backend cpu|cuda|auto] [--repeat N] [--device]
// --device (CUDA): the rays and outputs in device memory (no copies), as torch tensors would be.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "prt/pointrt.h"

int main(int argc, char** argv) {
    if (argc < 3) {
        std::fprintf(stderr, "usage: %s POOL RAYS.f32 [--backend NAME] [--repeat N] [--device]\n", argv[0]);
        return 2;
    }
    pointrt::Options options;
    int repeat = 3;
    bool device = false;
    for (int i = 3; i < argc; ++i) {
        if (!std::strcmp(argv[i], "--backend") && i + 1 < argc)
            options.backend = argv[++i];
        else if (!std::strcmp(argv[i], "--repeat") && i + 1 < argc)
            repeat = std::max(1, std::atoi(argv[++i]));
        else if (!std::strcmp(argv[i], "--device"))
            device = true;
        else {
            std::fprintf(stderr, "prt-bench-cast: unknown argument %s\n", argv[i]);
            return 2;
        }
    }
    try {
        std::ifstream in(argv[2], std::ios::binary | std::ios::ate);
        if (!in) throw pointrt::Error(std::string(argv[2]) + ": cannot read");
        const std::size_t bytes = static_cast<std::size_t>(in.tellg());
        if (bytes % 24 != 0)
            throw pointrt::Error(std::string(argv[2]) + ": not a whole number of 24-byte rays");
        const std::size_t n = bytes / 24;
        std::vector<float> rec(n * 6);
        in.seekg(0);
        in.read(reinterpret_cast<char*>(rec.data()), static_cast<std::streamsize>(bytes));
        pointrt::Scene scene = pointrt::Scene::open(argv[1], options);
        std::printf("cpp: backend %s on %s\n", scene.info().backend.c_str(), scene.info().device.c_str());
        pointrt::RayArrays rays;
        rays.count = n;
        rays.origin_stride = rays.direction_stride = 24;  // interleaved records, read in place
        // The same outputs the Python module returns by default: every field.
        std::vector<std::uint8_t> hit(n), valid(n);
        std::vector<float> t(n), position(n * 3), normal(n * 3), color(n * 3);
        std::vector<std::int32_t> model(n);
        std::vector<std::int64_t> element(n);
        pointrt::HitArrays out{hit.data(),    valid.data(), t.data(),     position.data(),
                               normal.data(), color.data(), model.data(), element.data()};
        rays.origins = rec.data();
        rays.directions = rec.data() + 3;
        // --device: the rays and every output in device memory (freed at exit).
        struct DeviceBlock {
            void* p = nullptr;
            explicit DeviceBlock(std::size_t b) : p(pointrt::device_malloc(b)) {}
            ~DeviceBlock() { pointrt::device_free(p); }
        };
        std::vector<std::unique_ptr<DeviceBlock>> blocks;
        auto dev = [&](std::size_t b) {
            blocks.push_back(std::make_unique<DeviceBlock>(b));
            return blocks.back()->p;
        };
        pointrt::HitArrays d_out;
        if (device) {
            void* d_rec = dev(bytes);
            pointrt::host_to_device(d_rec, rec.data(), bytes);
            rays.origins = d_rec;
            rays.directions = static_cast<float*>(d_rec) + 3;
            rays.memory = pointrt::Memory::device;
            d_out.hit = static_cast<std::uint8_t*>(dev(n));
            d_out.valid = static_cast<std::uint8_t*>(dev(n));
            d_out.t = static_cast<float*>(dev(n * 4));
            d_out.position = static_cast<float*>(dev(n * 12));
            d_out.normal = static_cast<float*>(dev(n * 12));
            d_out.color = static_cast<float*>(dev(n * 12));
            d_out.model = static_cast<std::int32_t*>(dev(n * 4));
            d_out.element = static_cast<std::int64_t*>(dev(n * 8));
            d_out.memory = pointrt::Memory::device;
        }
        double best = 1e300;
        std::size_t hits = 0;
        for (int r = 0; r < repeat; ++r) {
            const auto t0 = std::chrono::steady_clock::now();
            const pointrt::CastStats st = scene.cast(rays, device ? d_out : out);
            if (device) pointrt::device_to_host(hit.data(), d_out.hit, n);
            const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            hits = static_cast<std::size_t>(std::count(hit.begin(), hit.end(), 1));
            std::printf("cpp: %zu rays in %.4f s = %.2f Mrays/s (kernel %.3f ms, hits %zu)\n", n, s,
                        n / s * 1e-6, st.device_ms, hits);
            best = std::min(best, s);
        }
        std::printf("cpp best: %.2f Mrays/s\n", n / best * 1e-6);
        return 0;
    } catch (const pointrt::Error& e) {
        std::fprintf(stderr, "prt-bench-cast: %s\n", e.what());
        return 1;
    }
}
