#include "camera_path.h"

#include <cmath>
#include <fstream>
#include <sstream>

#include "prt/error.h"

namespace prt::player {

std::vector<CameraKey> read_camera_path(const std::filesystem::path& file) {
    std::ifstream in(file);
    if (!in) throw Error(file.string() + ": cannot open camera path");
    std::vector<CameraKey> keys;
    std::string line;
    for (int number = 1; std::getline(in, line); ++number) {
        const auto hash = line.find('#');
        if (hash != std::string::npos) line.resize(hash);
        std::istringstream ss(line);
        std::vector<double> v;
        std::string tok;
        while (ss >> tok) {
            try {
                std::size_t used = 0;
                v.push_back(std::stod(tok, &used));
                if (used != tok.size() || !std::isfinite(v.back())) throw std::invalid_argument(tok);
            } catch (const std::exception&) {
                throw Error(file.string() + ":" + std::to_string(number) + ": '" + tok +
                            "' is not a finite number");
            }
        }
        if (v.empty()) continue;
        if (v.size() != 6 && v.size() != 7) {
            throw Error(file.string() + ":" + std::to_string(number) +
                        ": expected 6 or 7 numbers (px py pz lx ly lz [fov]), got " +
                        std::to_string(v.size()));
        }
        CameraKey k;
        k.position = {v[0], v[1], v[2]};
        k.look_at = {v[3], v[4], v[5]};
        if (k.position == k.look_at)
            throw Error(file.string() + ":" + std::to_string(number) + ": position equals look-at point");
        if (v.size() == 7) {
            if (!(v[6] > 0 && v[6] < 180))
                throw Error(file.string() + ":" + std::to_string(number) + ": fov must be in (0, 180)");
            k.fov_y_degrees = v[6];
        }
        keys.push_back(k);
    }
    if (keys.empty()) throw Error(file.string() + ": camera path has no keys");
    return keys;
}

scene::Camera orbit_camera(const scene::Camera& base, std::uint32_t frame, double degrees_per_frame) {
    scene::Camera c = base;
    const double a = frame * degrees_per_frame * 3.14159265358979323846 / 180.0;
    // Rodrigues' rotation of the eye about the unit up k through the look-at point:
    // v' = v cos a + (k x v) sin a + k (k . v)(1 - cos a).
    const scene::Vec3& u = base.up;
    const double ul = std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    const scene::Vec3 k = ul > 0 ? scene::Vec3{u[0] / ul, u[1] / ul, u[2] / ul} : scene::Vec3{0, 1, 0};
    const scene::Vec3 v{base.position[0] - base.look_at[0], base.position[1] - base.look_at[1],
                        base.position[2] - base.look_at[2]};
    const scene::Vec3 kxv{k[1] * v[2] - k[2] * v[1], k[2] * v[0] - k[0] * v[2], k[0] * v[1] - k[1] * v[0]};
    const double kv = k[0] * v[0] + k[1] * v[1] + k[2] * v[2];
    const double ca = std::cos(a), sa = std::sin(a);
    for (int i = 0; i < 3; ++i)
        c.position[i] = base.look_at[i] + v[i] * ca + kxv[i] * sa + k[i] * kv * (1 - ca);
    return c;
}

scene::Camera path_camera(const scene::Camera& base, const std::vector<CameraKey>& path,
                          std::uint32_t frame) {
    scene::Camera c = base;
    if (path.empty()) return c;
    const CameraKey& k = path[frame % path.size()];
    c.position = k.position;
    c.look_at = k.look_at;
    if (k.fov_y_degrees > 0) c.fov_y_degrees = k.fov_y_degrees;
    return c;
}

}  // namespace prt::player
