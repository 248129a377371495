// PointRT example: picking (prt/pointrt.h). The ray through pixel (PX, PY) of the scene's default
// view (WIDTH x HEIGHT, row 0 at the top) is cast; the hit's position, normal, model and element
// (the source point of splats) are printed.
//
//     prt_example_picking scan.pool PX PY [WIDTH HEIGHT] [--backend NAME]
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "prt/pointrt.h"

int main(int argc, char** argv) {
    if (argc != 4 && argc != 6 && argc != 8) {
        std::fprintf(stderr, "usage: %s POOL PX PY [WIDTH HEIGHT] [--backend NAME]\n", argv[0]);
        return 2;
    }
    try {
        pointrt::Options options;
        if (argc == 8) options.backend = argv[7];
        const unsigned w = argc >= 6 ? std::atoi(argv[4]) : 512, h = argc >= 6 ? std::atoi(argv[5]) : 512;
        const double px = std::atof(argv[2]), py = std::atof(argv[3]);
        pointrt::Scene scene = pointrt::Scene::open(argv[1], options);
        const pointrt::Camera cam = scene.default_camera(w, h);
        // The pinhole camera's frame: forward, right, up; the pixel's direction through its centre.
        double f[3], r[3], u[3];
        for (int k = 0; k < 3; ++k) f[k] = cam.look_at[k] - cam.eye[k];
        auto normalize = [](double* v) {
            const double l = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
            for (int k = 0; k < 3; ++k) v[k] /= l;
        };
        normalize(f);
        r[0] = f[1] * cam.up[2] - f[2] * cam.up[1];
        r[1] = f[2] * cam.up[0] - f[0] * cam.up[2];
        r[2] = f[0] * cam.up[1] - f[1] * cam.up[0];
        normalize(r);
        u[0] = r[1] * f[2] - r[2] * f[1];
        u[1] = r[2] * f[0] - r[0] * f[2];
        u[2] = r[0] * f[1] - r[1] * f[0];
        const double tan_half = std::tan(cam.fov_y_degrees * 3.14159265358979323846 / 360.0);
        const double sx = (2.0 * (px + 0.5) / w - 1.0) * tan_half * w / h;
        const double sy = (1.0 - 2.0 * (py + 0.5) / h) * tan_half;
        pointrt::Ray ray;
        ray.origin = cam.eye;
        for (int k = 0; k < 3; ++k) ray.direction[k] = f[k] + sx * r[k] + sy * u[k];
        const pointrt::Hit hit = scene.cast(std::vector<pointrt::Ray>{ray})[0];
        if (!hit.hit) {
            std::printf("pixel (%g, %g): nothing\n", px, py);
            return 0;
        }
        const double len =
            std::sqrt(ray.direction[0] * ray.direction[0] + ray.direction[1] * ray.direction[1] +
                      ray.direction[2] * ray.direction[2]);
        std::printf("pixel (%g, %g): model %d, element %lld, distance %.5f\n", px, py, hit.model,
                    static_cast<long long>(hit.element), hit.t * len);
        std::printf("position %.5f %.5f %.5f\n", hit.position[0], hit.position[1], hit.position[2]);
        std::printf("normal %.5f %.5f %.5f\n", hit.normal[0], hit.normal[1], hit.normal[2]);
        return 0;
    } catch (const pointrt::Error& e) {
        std::fprintf(stderr, "%s\n", e.what());
        return 1;
    }
}
