// PointRT example: visibility between two points of a scan (prt/pointrt.h). One occlusion query
// on the segment from A to B: the ray A + t (B - A), t in [0, 1 - margin), so B's own surface does
// not count as a blocker. Prints "visible" or "blocked".
//
//     prt_example_visibility scan.pool AX AY AZ BX BY BZ [--backend cpu|cuda|auto]
#include <cstdio>
#include <cstdlib>
#include <string>

#include "prt/pointrt.h"

int main(int argc, char** argv) {
    if (argc != 8 && argc != 10) {
        std::fprintf(stderr, "usage: %s POOL AX AY AZ BX BY BZ [--backend NAME]\n", argv[0]);
        return 2;
    }
    try {
        pointrt::Options options;
        if (argc == 10) options.backend = argv[9];
        pointrt::Scene scene = pointrt::Scene::open(argv[1], options);
        const double a[3] = {std::atof(argv[2]), std::atof(argv[3]), std::atof(argv[4])};
        const double b[3] = {std::atof(argv[5]), std::atof(argv[6]), std::atof(argv[7])};
        pointrt::Ray ray;
        ray.origin = {a[0], a[1], a[2]};
        ray.direction = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};  // t = 1 at B
        ray.t_max = 0.999f;  // a margin: splats around B blend in slightly before it
        const std::uint8_t blocked = scene.occluded(std::vector<pointrt::Ray>{ray})[0];
        std::printf("%s\n", blocked ? "blocked" : "visible");
        // Where the first blocker lies, when there is one.
        if (blocked) {
            const pointrt::Hit h = scene.cast(std::vector<pointrt::Ray>{ray})[0];
            if (h.hit)
                std::printf("first blocker at t = %.4f: (%.4f, %.4f, %.4f)\n", h.t, h.position[0],
                            h.position[1], h.position[2]);
        }
        return 0;
    } catch (const pointrt::Error& e) {
        std::fprintf(stderr, "%s\n", e.what());
        return 1;
    }
}
