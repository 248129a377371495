#include "prt/runtime/scan_frame.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "prt/symmetric_eigen.h"

namespace prt::rt {

namespace {

constexpr double k_pi = 3.14159265358979323846;

DVec3 to_d(const pool::Float3& f) {
    return {f.x, f.y, f.z};
}

/// splitmix64 (Steele, Lea and Flood 2014): a small, portable, seeded generator.
struct Rng {
    std::uint64_t state;
    std::uint64_t next() {
        std::uint64_t z = (state += 0x9e3779b97f4a7c15ull);
        z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
        z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
        return z ^ (z >> 31);
    }
    std::size_t below(std::size_t n) { return static_cast<std::size_t>(next() % n); }
};

/// Centroid and covariance eigen-decomposition of the points `idx` of `p`.
void fit_plane(const std::vector<DVec3>& p, const std::vector<std::size_t>& idx, DVec3& centroid,
               DVec3& values, std::array<DVec3, 3>& vectors) {
    centroid = {0, 0, 0};
    for (std::size_t i : idx) centroid = add(centroid, p[i]);
    centroid = mul(centroid, 1.0 / static_cast<double>(std::max<std::size_t>(idx.size(), 1)));
    std::array<DVec3, 3> c{};
    for (std::size_t i : idx) {
        const DVec3 d = sub(p[i], centroid);
        for (int r = 0; r < 3; ++r)
            for (int k = 0; k < 3; ++k) c[r][k] += d[r] * d[k];
    }
    for (auto& row : c) row = mul(row, 1.0 / static_cast<double>(std::max<std::size_t>(idx.size(), 1)));
    const SymmetricEigen e = symmetric_eigen(c);
    values = e.values;
    for (int i = 0; i < 3; ++i) vectors[i] = normalized(e.vectors[i]);
}

/// The nearest-rank percentile q of `v` (reordered).
double percentile(std::vector<double>& v, double q) {
    const auto k = static_cast<std::size_t>(std::llround(q * static_cast<double>(v.size() - 1)));
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
    return v[k];
}

std::string percent(double f) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.1f %%", 100.0 * f);
    return buf;
}

/// Snaps a unit vector to the nearest signed axis when within `degrees` of it.
DVec3 snap(const DVec3& v, double degrees, bool& snapped) {
    int axis = 0;
    for (int a = 1; a < 3; ++a)
        if (std::fabs(v[a]) > std::fabs(v[axis])) axis = a;
    snapped = std::fabs(v[axis]) >= std::cos(degrees * k_pi / 180.0);
    if (!snapped) return v;
    DVec3 r{0, 0, 0};
    r[axis] = v[axis] > 0 ? 1.0 : -1.0;
    return r;
}

/// +1 or -1: the sign that makes `n` agree with +y (else +z, else +x): the file's own convention
/// when the data cannot tell.
double convention_sign(const DVec3& n) {
    if (std::fabs(n[1]) > 1e-9) return n[1] > 0 ? 1.0 : -1.0;
    if (std::fabs(n[2]) > 1e-9) return n[2] > 0 ? 1.0 : -1.0;
    return n[0] >= 0 ? 1.0 : -1.0;
}

}  // namespace

std::string direction_name(const DVec3& v) {
    static const char* names[3] = {"x", "y", "z"};
    for (int a = 0; a < 3; ++a) {
        if (std::fabs(v[a]) == 1.0 && v[(a + 1) % 3] == 0.0 && v[(a + 2) % 3] == 0.0)
            return std::string(v[a] > 0 ? "+" : "-") + names[a];
    }
    char buf[96];
    std::snprintf(buf, sizeof buf, "(%.3f, %.3f, %.3f)", v[0], v[1], v[2]);
    return buf;
}

Box robust_bounds(const std::vector<DVec3>& points, double reach, std::vector<DVec3>* kept) {
    Box b;
    if (points.empty()) return b;
    DVec3 lo{}, hi{};
    std::vector<double> v(points.size());
    for (int a = 0; a < 3; ++a) {
        for (std::size_t i = 0; i < points.size(); ++i) v[i] = points[i][a];
        lo[a] = percentile(v, 0.01);
        hi[a] = percentile(v, 0.99);
    }
    const double grow = reach * length(sub(hi, lo));
    constexpr double k_inf = std::numeric_limits<double>::infinity();
    b.lo = {k_inf, k_inf, k_inf};
    b.hi = {-k_inf, -k_inf, -k_inf};
    for (const DVec3& p : points) {
        bool inside = true;
        for (int a = 0; a < 3; ++a) inside = inside && p[a] >= lo[a] - grow && p[a] <= hi[a] + grow;
        if (!inside) {
            ++b.outside;
            continue;
        }
        if (kept) kept->push_back(p);
        for (int a = 0; a < 3; ++a) {
            b.lo[a] = std::min(b.lo[a], p[a]);
            b.hi[a] = std::max(b.hi[a], p[a]);
        }
    }
    b.valid = true;
    return b;
}

namespace {

/// The points detect_up looks at: a fixed-seed sample (with replacement) of the finite positions,
/// in the pool's local frame, with their unit normals when the pool has normals.
struct UpSample {
    std::vector<DVec3> pts, nrm;
    bool have_normals = false;
    double tol = 0;         ///< plane inlier distance
    double cos_normal = 0;  ///< inliers' normals within this cosine of the plane's
};

/// The dominant plane of a sample: its inliers, unit normal n and a point p on it.
struct Plane {
    std::vector<std::size_t> inliers;
    DVec3 n{0, 1, 0}, p{0, 0, 0};
};

/// The sample's points within tol of the plane (p0, nn) whose normals (when known) agree with it;
/// appended to `list` when not null.
std::size_t plane_inliers(const UpSample& s, const DVec3& p0, const DVec3& nn,
                          std::vector<std::size_t>* list) {
    std::size_t count = 0;
    for (std::size_t i = 0; i < s.pts.size(); ++i) {
        if (std::fabs(dot(sub(s.pts[i], p0), nn)) > s.tol) continue;
        if (s.have_normals && std::fabs(dot(s.nrm[i], nn)) < s.cos_normal) continue;
        ++count;
        if (list) list->push_back(i);
    }
    return count;
}

/// Rule (1)'s plane: RANSAC on the sample (Fischler and Bolles 1981), then a least-squares refit of
/// its inliers, twice.
Plane dominant_plane(const UpSample& s, double diag, std::uint32_t iterations, Rng& rng) {
    Plane best;
    const std::vector<DVec3>& pts = s.pts;
    if (pts.size() < 3 || !(diag > 0)) return best;
    std::size_t best_count = 0;
    for (std::uint32_t it = 0; it < iterations; ++it) {
        const DVec3& a = pts[rng.below(pts.size())];
        const DVec3& b = pts[rng.below(pts.size())];
        const DVec3& c = pts[rng.below(pts.size())];
        const DVec3 cr = cross(sub(b, a), sub(c, a));
        if (length(cr) <= 1e-9 * diag * diag) continue;
        const DVec3 nn = normalized(cr);
        const std::size_t count = plane_inliers(s, a, nn, nullptr);
        if (count > best_count) {
            best_count = count;
            best.n = nn;
            best.p = a;
        }
    }
    if (best_count >= 3) {
        for (int refit = 0; refit < 2; ++refit) {  // least squares on the inliers, recounted
            std::vector<std::size_t> list;
            plane_inliers(s, best.p, best.n, &list);
            if (list.size() < 3) break;
            DVec3 values{};
            std::array<DVec3, 3> vectors{};
            fit_plane(pts, list, best.p, values, vectors);
            best.n = vectors[0];
        }
        plane_inliers(s, best.p, best.n, &best.inliers);
    }
    return best;
}

/// The sample's points off the plane (beyond 2 tol) over the plane's own footprint (cells of a
/// 32 x 32 grid over its inliers that hold one), above (`over`) and below (`under`) it.
void footprint_sides(const UpSample& s, const Plane& plane, const DVec3& nn, std::size_t& over,
                     std::size_t& under) {
    const std::vector<DVec3>& pts = s.pts;
    const DVec3 a = normalized(cross(nn, std::fabs(nn[0]) < 0.9 ? DVec3{1, 0, 0} : DVec3{0, 1, 0}));
    const DVec3 b = cross(nn, a);
    constexpr int g = 32;
    double lo_a = std::numeric_limits<double>::infinity(), hi_a = -lo_a, lo_b = lo_a, hi_b = -lo_a;
    for (std::size_t i : plane.inliers) {
        const DVec3 d = sub(pts[i], plane.p);
        lo_a = std::min(lo_a, dot(d, a));
        hi_a = std::max(hi_a, dot(d, a));
        lo_b = std::min(lo_b, dot(d, b));
        hi_b = std::max(hi_b, dot(d, b));
    }
    const double sa = std::max(hi_a - lo_a, 1e-30) / g, sb = std::max(hi_b - lo_b, 1e-30) / g;
    auto cell = [&](const DVec3& d) -> int {
        const double u = (dot(d, a) - lo_a) / sa, v = (dot(d, b) - lo_b) / sb;
        if (!(u >= 0 && u < g && v >= 0 && v < g)) return -1;
        return static_cast<int>(u) * g + static_cast<int>(v);
    };
    std::vector<char> occupied(g * g, 0);
    for (std::size_t i : plane.inliers) {
        const int c = cell(sub(pts[i], plane.p));
        if (c >= 0) occupied[static_cast<std::size_t>(c)] = 1;
    }
    over = under = 0;
    for (const DVec3& p : pts) {
        const DVec3 d = sub(p, plane.p);
        const double h = dot(d, nn);
        if (std::fabs(h) <= 2 * s.tol) continue;
        const int c = cell(d);
        if (c < 0 || !occupied[static_cast<std::size_t>(c)]) continue;
        over += h > 0;
        under += h < 0;
    }
}

/// Turns nn around when more of the sample lies on its negative side (`negative` > `positive`),
/// swapping the two counts so that `positive` counts the side nn now points to.
void toward_larger(DVec3& nn, std::size_t& positive, std::size_t& negative) {
    if (negative > positive) {
        nn = mul(nn, -1.0);
        std::swap(positive, negative);
    }
}

/// Rule (1)'s sign: toward the sensors (a scanner sees the top of the floor or table it scans);
/// else toward the side of what stands on the plane over its footprint (a scanner that sees the
/// top of a floor or table sees only what stands on it: the floor seen beyond a table's edge,
/// below its plane, lies outside the table's footprint); else toward the side most other points
/// lie on (objects stand on a floor); else the convention. Sets out.up and out.description.
void orient_plane(const UpInput& in, const UpSample& s, const Plane& plane, UpDetection& out) {
    DVec3 nn = plane.n;
    std::string why;
    int votes = 0;
    for (const pool::Sensor& sensor : in.sensors) {
        const DVec3 sp{sensor.position[0], sensor.position[1], sensor.position[2]};
        const double side =
            sensor.kind == pool::k_sensor_direction ? dot(sp, nn) : dot(sub(sub(sp, in.origin), plane.p), nn);
        votes += side > 0 ? 1 : side < 0 ? -1 : 0;
    }
    std::size_t over = 0, under = 0;
    footprint_sides(s, plane, nn, over, under);
    if (votes != 0) {
        nn = mul(nn, votes > 0 ? 1.0 : -1.0);
        why = "toward the sensors";
    } else if (std::max(over, under) >= 2 * std::min(over, under) + 20) {
        toward_larger(nn, over, under);
        why = "toward the side of what stands on it (" + std::to_string(over) +
              " of the sample above its footprint, " + std::to_string(under) + " below)";
    } else {
        std::size_t above = 0, below = 0;
        for (const DVec3& p : s.pts) {
            const double d = dot(sub(p, plane.p), nn);
            above += d > 2 * s.tol;
            below += d < -2 * s.tol;
        }
        if (above != below) {
            toward_larger(nn, above, below);
            why = "toward the side most other points lie on (" + std::to_string(above) +
                  " of the sample above, " + std::to_string(below) + " below)";
        } else {
            nn = mul(nn, convention_sign(nn));
            why = "no side holds more points: signed toward +y";
        }
    }
    out.up = nn;
    out.description =
        "a dominant plane holds " + percent(out.plane_fraction) + " of the points: its normal, " + why;
}

/// Rule (2)'s plane: the largest set of the (first 64) sensor directions within `band` of a plane
/// through three of them, and that plane's normal fitted to the set. True when the set holds at
/// least half of them and spans the plane.
bool sensor_plane(const std::vector<DVec3>& sensor_dirs, double band, std::vector<std::size_t>& best_set,
                  DVec3& plane_n) {
    const std::size_t ns = std::min<std::size_t>(sensor_dirs.size(), 64);
    if (ns >= 3) {
        for (std::size_t i = 0; i < ns; ++i)
            for (std::size_t j = i + 1; j < ns; ++j)
                for (std::size_t k = j + 1; k < ns; ++k) {
                    const DVec3 cr =
                        cross(sub(sensor_dirs[j], sensor_dirs[i]), sub(sensor_dirs[k], sensor_dirs[i]));
                    if (length(cr) < 1e-6) continue;
                    const DVec3 nn = normalized(cr);
                    std::vector<std::size_t> set;
                    for (std::size_t q = 0; q < ns; ++q)
                        if (std::fabs(dot(sub(sensor_dirs[q], sensor_dirs[i]), nn)) <= band) set.push_back(q);
                    if (set.size() > best_set.size()) best_set = std::move(set);
                }
    }
    if (!(best_set.size() >= 3 && 2 * best_set.size() >= ns)) return false;
    DVec3 c{}, values{};
    std::array<DVec3, 3> vectors{};
    fit_plane(sensor_dirs, best_set, c, values, vectors);
    plane_n = vectors[0];
    // Spread over the plane (not bunched in one direction: an in-plane variance of 0.01 at least,
    // directions about 8 degrees from their mean or more), and flat (the variance along the normal
    // within the band's).
    return values[1] >= 0.01 && values[0] <= band * band;
}

/// Rule (2)'s sign: toward the side the sensors lean to; else toward the side more surface normals
/// face (the face an object rests on is not scanned); else the convention. Sets out.up and
/// out.description.
void orient_sensor_plane(const std::vector<DVec3>& sensor_dirs, const std::vector<std::size_t>& best_set,
                         const DVec3& plane_n, const std::vector<DVec3>& nrm, UpDetection& out) {
    DVec3 nn = plane_n;
    std::string why;
    DVec3 mean{0, 0, 0};
    for (std::size_t q : best_set) mean = add(mean, sensor_dirs[q]);
    mean = mul(mean, 1.0 / static_cast<double>(best_set.size()));
    const double lean = dot(mean, nn);
    std::size_t up_faces = 0, down_faces = 0;
    for (const DVec3& v : nrm) {
        up_faces += dot(v, nn) > 0.5;
        down_faces += dot(v, nn) < -0.5;
    }
    if (std::fabs(lean) >= std::sin(5 * k_pi / 180.0)) {
        nn = mul(nn, lean > 0 ? 1.0 : -1.0);
        char buf[64];
        std::snprintf(buf, sizeof buf, "%.1f",
                      std::fabs(std::asin(std::clamp(lean, -1.0, 1.0))) * 180.0 / k_pi);
        why = std::string("toward the side the sensors lean to (") + buf + " degrees above their plane)";
    } else if (std::max(up_faces, down_faces) >=
               1.2 * static_cast<double>(std::min(up_faces, down_faces)) + 10) {
        toward_larger(nn, up_faces, down_faces);
        why = "toward the side more surface normals face (" + std::to_string(up_faces) +
              " of the sample against " + std::to_string(down_faces) +
              ": the face an object rests on is not scanned)";
    } else {
        nn = mul(nn, convention_sign(nn));
        why = "nothing tells the sides apart: signed toward +y";
    }
    out.up = nn;
    out.description = "the directions of " + std::to_string(best_set.size()) + " of " +
                      std::to_string(sensor_dirs.size()) +
                      " sensors span a plane (a turntable): its normal, " + why;
}

}  // namespace

UpDetection detect_up(const UpInput& in, const UpParams& params) {
    UpDetection out;
    const std::size_t n = in.positions.size();
    UpSample sample;
    sample.have_normals = in.normals.size() == n && n > 0;
    Rng rng{params.seed};
    const std::size_t m = std::min<std::size_t>(n, params.sample);
    sample.pts.reserve(m);
    for (std::size_t k = 0; k < m; ++k) {
        const std::size_t i = m == n ? k : rng.below(n);
        const DVec3 p = to_d(in.positions[i]);
        if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) continue;
        sample.pts.push_back(p);
        if (sample.have_normals) sample.nrm.push_back(normalized(to_d(in.normals[i])));
    }
    const Box box = robust_bounds(sample.pts);
    const DVec3 centre = mul(add(box.lo, box.hi), 0.5);
    const double diag = length(sub(box.hi, box.lo));
    sample.tol = params.tolerance * diag;
    sample.cos_normal = std::cos(params.normal_degrees * k_pi / 180.0);

    // (1) a dominant plane.
    const Plane plane = dominant_plane(sample, diag, params.iterations, rng);
    out.plane_fraction = sample.pts.empty() ? 0.0
                                            : static_cast<double>(plane.inliers.size()) /
                                                  static_cast<double>(sample.pts.size());
    out.plane_point = plane.p;

    // Sensors in the pool's local frame: unit directions from the points' centre toward each.
    std::vector<DVec3> sensor_dirs;
    for (const pool::Sensor& s : in.sensors) {
        const DVec3 sp{s.position[0], s.position[1], s.position[2]};
        if (s.kind == pool::k_sensor_direction) {
            sensor_dirs.push_back(normalized(sp));
        } else {
            const DVec3 d = normalized(sub(sub(sp, in.origin), centre));
            if (length(d) > 0) sensor_dirs.push_back(d);
        }
    }

    std::vector<std::size_t> best_set;
    DVec3 plane_n{0, 0, 0};
    if (out.plane_fraction >= params.min_plane_fraction && plane.inliers.size() >= 3) {
        out.rule = UpRule::plane;
        orient_plane(in, sample, plane, out);
    } else if (sensor_plane(sensor_dirs, std::sin(params.sensor_degrees * k_pi / 180.0), best_set, plane_n)) {
        out.rule = UpRule::sensor_plane;  // (2) sensor directions spanning a plane (a turntable)
        orient_sensor_plane(sensor_dirs, best_set, plane_n, sample.nrm, out);
    } else {
        out.rule = UpRule::fallback;
        out.up = {0, 1, 0};
        out.description = "no dominant plane (the largest holds " + percent(out.plane_fraction) +
                          " of the points, " + percent(params.min_plane_fraction) + " needed)" +
                          (sensor_dirs.size() >= 3 ? " and the sensors span no plane" : "") + ": +y";
    }
    out.up = snap(normalized(out.up), params.snap_degrees, out.snapped);
    if (out.snapped && out.rule != UpRule::fallback)
        out.description += " (snapped to " + direction_name(out.up) + ")";
    return out;
}

}  // namespace prt::rt
