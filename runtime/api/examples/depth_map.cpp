// PointRT example: a depth map from a scanner position (prt/pointrt.h). One ray per pixel of an
// equirectangular (azimuth x elevation) grid around the position, cast as one batch through the
// array interface; the range image is written as a 16-bit PGM (range / max range * 65535, 0 where
// nothing was hit) and its hit count and range bounds are printed.
//
//     prt_example_depth_map scan.pool X Y Z OUT.pgm [WIDTH HEIGHT] [--backend NAME]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include "prt/pointrt.h"

int main(int argc, char** argv) {
    if (argc != 6 && argc != 8 && argc != 10) {
        std::fprintf(stderr, "usage: %s POOL X Y Z OUT.pgm [WIDTH HEIGHT] [--backend NAME]\n", argv[0]);
        return 2;
    }
    try {
        pointrt::Options options;
        if (argc == 10) options.backend = argv[9];
        const unsigned w = argc >= 8 ? std::atoi(argv[6]) : 720, h = argc >= 8 ? std::atoi(argv[7]) : 360;
        if (w == 0 || h == 0) throw pointrt::Error("WIDTH and HEIGHT must be positive");
        pointrt::Scene scene = pointrt::Scene::open(argv[1], options);
        const double eye[3] = {std::atof(argv[2]), std::atof(argv[3]), std::atof(argv[4])};
        // Rays: from the scanner, one direction per pixel (z up).
        const std::size_t n = static_cast<std::size_t>(w) * h;
        std::vector<float> dirs(n * 3);
        const double pi = 3.14159265358979323846;
        for (unsigned y = 0; y < h; ++y) {
            const double elev = pi / 2 - (y + 0.5) * pi / h;
            for (unsigned x = 0; x < w; ++x) {
                const double az = (x + 0.5) * 2 * pi / w;
                float* d = &dirs[(static_cast<std::size_t>(y) * w + x) * 3];
                d[0] = static_cast<float>(std::cos(elev) * std::cos(az));
                d[1] = static_cast<float>(std::cos(elev) * std::sin(az));
                d[2] = static_cast<float>(std::sin(elev));
            }
        }
        pointrt::RayArrays rays;
        rays.count = n;
        rays.origins_f64 = true;  // world coordinates of a georeferenced scan keep their precision
        std::vector<double> origins(n * 3);
        for (std::size_t i = 0; i < n; ++i) std::copy(eye, eye + 3, &origins[i * 3]);
        rays.origins = origins.data();
        rays.directions = dirs.data();
        std::vector<std::uint8_t> hit(n);
        std::vector<float> t(n);
        pointrt::HitArrays out;
        out.hit = hit.data();
        out.t = t.data();
        const pointrt::CastStats st = scene.cast(rays, out);
        std::size_t hits = 0;
        float lo = INFINITY, hi = 0;
        for (std::size_t i = 0; i < n; ++i)
            if (hit[i]) {
                ++hits;
                lo = std::min(lo, t[i]);
                hi = std::max(hi, t[i]);
            }
        std::ofstream f(argv[5], std::ios::binary);
        if (!f) throw pointrt::Error(std::string(argv[5]) + ": cannot write");
        f << "P5\n" << w << " " << h << "\n65535\n";
        for (std::size_t i = 0; i < n; ++i) {
            const unsigned v =
                hit[i] && hi > 0 ? static_cast<unsigned>(std::lround(t[i] / hi * 65535.0)) : 0u;
            const unsigned char be[2] = {static_cast<unsigned char>(v >> 8),
                                         static_cast<unsigned char>(v & 0xff)};
            f.write(reinterpret_cast<const char*>(be), 2);
        }
        if (!f) throw pointrt::Error(std::string(argv[5]) + ": write failed");
        std::printf("%zu of %zu rays hit; range %.4f .. %.4f; %.3f s (%s)\n", hits, n, hits ? lo : 0.0f, hi,
                    st.seconds, scene.info().backend.c_str());
        return 0;
    } catch (const pointrt::Error& e) {
        std::fprintf(stderr, "%s\n", e.what());
        return 1;
    }
}
