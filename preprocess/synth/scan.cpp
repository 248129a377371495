#include "scan.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <unordered_set>

#include "prt/error.h"
#include "prt/parallel.h"
#include "synth_random.h"

namespace prt::synth {
namespace {

using namespace detail;

constexpr double k_pi = 3.14159265358979323846;
constexpr double k_deg = k_pi / 180.0;

constexpr std::uint64_t k_stream_ray = 16;            // per ray: dropout, range noise, intensity noise
constexpr std::uint64_t k_stream_outlier_pick = 17;   // which returns become mixed-pixel outliers
constexpr std::uint64_t k_stream_outlier_shift = 18;  // each one's displacement
constexpr std::uint64_t k_stream_uniform = 19;        // uniform outliers

/// Mixed-pixel displacement, a fraction of the model size: U(lo, hi), either sign.
constexpr double k_outlier_min = 0.05, k_outlier_max = 0.25;
/// A displacement towards the scanner leaves at least this fraction of the range.
constexpr double k_outlier_keep_range = 0.1;
/// Uniform outliers fill the bounding box grown by this fraction of the size on every side.
constexpr double k_uniform_margin = 0.1;
/// Albedo of every part of a shape other than the room (whose parts' albedo is their color's
/// luminance, so the red and green walls are darker than the white ones).
constexpr double k_albedo = 0.8;
/// The most rays a scan may cast (its grid before the field's cone is cut out), and the most scan
/// lines (each costs ~72 bytes of bookkeeping; 1e7 is a line step of 3.6e-5 degrees all round).
constexpr double k_max_rays = 4294967295.0;
constexpr double k_max_lines = 1e7;

std::string num(double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.10g", v);
    return buf;
}
std::string vec_text(const Vec3& v) {
    return num(v[0]) + "," + num(v[1]) + "," + num(v[2]);
}

/// The scanner head's frame: axis a (up), azimuth 0 along e1, azimuth 90 along e2 = a x e1.
/// For a = +y: e1 = +z, e2 = +x.
struct Frame {
    Vec3 a, e1, e2;
    explicit Frame(const Vec3& axis) {
        a = mul(axis, 1.0 / length(axis));
        const Vec3 helper = std::fabs(a[2]) < 0.9 ? Vec3{0, 0, 1} : Vec3{1, 0, 0};
        e1 = sub(helper, mul(a, dot(helper, a)));
        e1 = mul(e1, 1.0 / length(e1));
        e2 = cross(a, e1);
    }
    Vec3 direction(double azimuth_deg, double elevation_deg) const {
        const double ph = azimuth_deg * k_deg, th = elevation_deg * k_deg;
        const double c = std::cos(th);
        return add(add(mul(e1, c * std::cos(ph)), mul(e2, c * std::sin(ph))), mul(a, std::sin(th)));
    }
};

/// One scanner's field: a grid of azimuth indices [k0, k1] x elevation indices [j0, j1] (angles
/// are index x step), and, outside the bounding sphere, the cone that holds the shape.
struct Field {
    bool full = false;
    double az[2] = {0, 0}, el[2] = {0, 0};  // degrees
    std::int64_t k0 = 0, k1 = -1, j0 = 0, j1 = -1;
    Vec3 toward{};         // cone axis (unit), when !full
    double cos_half = -1;  // rays with dot(d, toward) below this miss the bounding sphere
};

Field make_field(const ScanOptions& o, const Frame& f, const Vec3& scanner) {
    const auto box = shape_bounds(o.shape);
    const Vec3 centre = mul(add(box[0], box[1]), 0.5);
    const double radius = 0.5 * length(sub(box[1], box[0])) * (1 + 1e-9) + 1e-300;
    bool inside_box = true;
    for (int a = 0; a < 3; ++a) inside_box = inside_box && scanner[a] > box[0][a] && scanner[a] < box[1][a];
    const Vec3 w = sub(centre, scanner);
    const double dist = length(w);
    Field fd;
    if (inside_box || dist <= radius) {
        fd.full = true;
        fd.az[0] = 0;
        fd.az[1] = 360;
        fd.el[0] = -90 + o.blind_cone_degrees;
        fd.el[1] = 90;
    } else {
        fd.toward = mul(w, 1.0 / dist);
        const double half = std::asin(radius / dist);
        fd.cos_half = std::cos(half) * (1 - 1e-12);
        const double el_c = std::asin(std::clamp(dot(fd.toward, f.a), -1.0, 1.0)) / k_deg;
        const double az_c = std::atan2(dot(fd.toward, f.e2), dot(fd.toward, f.e1)) / k_deg;
        const double half_deg = half / k_deg;
        fd.el[0] = std::max(-90.0, el_c - half_deg);
        fd.el[1] = std::min(90.0, el_c + half_deg);
        if (el_c + half_deg >= 90 || el_c - half_deg <= -90) {
            fd.az[0] = 0;  // the cone holds a pole: every azimuth
            fd.az[1] = 360;
        } else {
            // The widest azimuth of a spherical cap of angular radius `half` centred at elevation
            // el_c: sin(d_az) = sin(half) / cos(el_c).
            const double s = std::min(1.0, std::sin(half) / std::cos(el_c * k_deg));
            const double d_az = std::asin(s) / k_deg;
            fd.az[0] = az_c - d_az;
            fd.az[1] = az_c + d_az;
        }
    }
    const double ls = o.line_step_degrees, ss = o.sample_step_degrees;
    if (fd.az[1] - fd.az[0] >= 360) {
        fd.k0 = 0;  // a full turn: k ls in [0, 360)
        fd.k1 = static_cast<std::int64_t>(std::ceil(360.0 / ls)) - 1;
        if (double(fd.k1) * ls >= 360.0 - 1e-9 * ls) --fd.k1;
        fd.az[0] = 0;
        fd.az[1] = 360;
    } else {
        fd.k0 = static_cast<std::int64_t>(std::ceil(fd.az[0] / ls));
        fd.k1 = static_cast<std::int64_t>(std::floor(fd.az[1] / ls));
    }
    // Elevations strictly inside (-90, 90): at a pole every line would repeat the same ray.
    fd.j0 = static_cast<std::int64_t>(std::ceil(fd.el[0] / ss));
    fd.j1 = static_cast<std::int64_t>(std::floor(fd.el[1] / ss));
    while (fd.j0 <= fd.j1 && double(fd.j0) * ss <= -90.0 + 1e-12) ++fd.j0;
    while (fd.j1 >= fd.j0 && double(fd.j1) * ss >= 90.0 - 1e-12) --fd.j1;
    return fd;
}

std::vector<std::string> part_names(const Shape& s) {
    switch (s.kind) {
        case ShapeKind::sphere:
            return {"sphere"};
        case ShapeKind::torus:
            return {"torus"};
        case ShapeKind::cube: {
            std::vector<std::string> v;
            for (int f = 0; f < 6; ++f) v.push_back(cube_face_name(f));
            return v;
        }
        case ShapeKind::plane:
            return {"plane"};
        case ShapeKind::room: {
            std::vector<std::string> v;
            for (int p = 0; p < k_room_part_count; ++p) v.push_back(room_part_name(p));
            return v;
        }
        case ShapeKind::ring:
            return {"inner", "outer", "top", "bottom"};
    }
    return {};
}

pool::Rgba8 part_color(const ScanOptions& o, int part) {
    if (o.colors == ColorMode::parts) {
        if (o.shape.kind == ShapeKind::room) return room_part_color(part);
        if (o.shape.kind == ShapeKind::cube) return cube_face_color(part);
    }
    return o.color;
}

double albedo(const Shape& s, int part) {
    if (s.kind != ShapeKind::room) return k_albedo;
    const pool::Rgba8 c = room_part_color(part);
    return (0.2126 * c.r + 0.7152 * c.g + 0.0722 * c.b) / 255.0;
}

/// One return before it becomes a point.
struct Return {
    Vec3 point;
    pool::Float3 normal;
    float intensity;
    std::int8_t part;
};

/// A scan line: scanner s, azimuth index k.
struct Line {
    std::uint32_t scanner;
    std::int64_t k;
};

struct LineCounts {
    std::uint64_t rays = 0, misses = 0, grazing = 0, dropout = 0;
};

}  // namespace

std::vector<Vec3> default_scanners(const Shape& shape, std::size_t count) {
    std::vector<Vec3> out;
    const auto box = shape_bounds(shape);
    const Vec3 centre = mul(add(box[0], box[1]), 0.5);
    const double size = shape_size(shape);
    for (std::size_t i = 0; i < count; ++i) {
        const double turn = 360.0 * double(i) / double(count);
        if (shape.kind == ShapeKind::room) {
            const double t = turn * k_deg;
            const Vec3 local{0.3 * std::sin(t), 0.05, 0.3 * std::cos(t)};
            out.push_back(add(centre, mul(local, size)));
        } else {
            const double az = (30.0 + turn) * k_deg, el = 35.0 * k_deg;
            const Vec3 dir{std::cos(el) * std::sin(az), std::sin(el), std::cos(el) * std::cos(az)};
            out.push_back(add(centre, mul(dir, 3 * size)));
        }
    }
    return out;
}

void validate(const ScanOptions& o) {
    validate(o.shape);
    enum Ends { closed, open_lo, open_hi };
    auto range = [](const char* name, double v, double lo, double hi, Ends ends, const char* what) {
        const bool ok =
            std::isfinite(v) && (ends == open_lo ? v > lo : v >= lo) && (ends == open_hi ? v < hi : v <= hi);
        if (!ok) throw Error(std::string(name) + " must be " + what + ", got " + num(v));
    };
    range("--sample-step", o.sample_step_degrees, 0, 90, open_lo, "in (0, 90] degrees");
    range("--line-step", o.line_step_degrees, 0, 360, open_lo, "in (0, 360] degrees");
    range("--blind-cone", o.blind_cone_degrees, 0, 90, open_hi, "in [0, 90) degrees");
    range("--max-incidence", o.max_incidence_degrees, 0, 90, open_lo, "in (0, 90] degrees");
    range("--dropout", o.dropout, 0, 1, closed, "in [0, 1]");
    range("--range-noise", o.range_noise, 0, 1, closed, "in [0, 1] (a fraction of the model size)");
    range("--range-noise-per-range", o.range_noise_per_range, 0, 1, closed,
          "in [0, 1] (sigma per unit of range)");
    range("--outliers", o.outliers, 0, 1, closed, "in [0, 1] (a fraction of the returns)");
    range("--uniform-outliers", o.uniform_outliers, 0, 1, closed, "in [0, 1] (a fraction of the returns)");
    range("--intensity-noise", o.intensity_noise, 0, 1, closed, "in [0, 1]");
    const double al = length(o.axis);
    if (!(std::isfinite(al) && al > 0))
        throw Error("--scan-axis must be a finite non-zero vector, got " + vec_text(o.axis));
    if (o.scanners.size() > pool::k_max_sensors)
        throw Error("at most " + std::to_string(pool::k_max_sensors) + " scanners, got " +
                    std::to_string(o.scanners.size()));
    const double size = shape_size(o.shape);
    for (const Vec3& s : o.scanners) {
        if (!std::isfinite(s[0]) || !std::isfinite(s[1]) || !std::isfinite(s[2]))
            throw Error("--scanner must be finite, got " + vec_text(s));
        const double sd = signed_distance(o.shape, s);
        const bool on = std::fabs(sd) <= 1e-9 * size;
        if (on || (sd < 0 && o.shape.kind != ShapeKind::plane)) {
            std::string where = on ? "on the surface of the " : "inside the ";
            if (!on && o.shape.kind == ShapeKind::room) {
                // Which solid holds it: an object, or the walls (outside the room's box).
                const Room& room = o.shape.room;
                const Vec3 p = mul(sub(s, o.shape.offset), 1.0 / o.shape.scale);
                const Vec3 q = sub(p, room.cube_center);
                const double yaw = room.cube_yaw_degrees * k_deg, c = std::cos(yaw), sn = std::sin(yaw);
                const Vec3 in_cube{c * q[0] - sn * q[2], q[1], sn * q[0] + c * q[2]};  // turned by -yaw
                where = closest(Sphere{room.sphere_radius}, sub(p, room.sphere_center)).signed_distance < 0
                            ? "inside the sphere of the "
                        : closest(Cube{room.cube_edge}, in_cube).signed_distance < 0
                            ? "inside the cube of the "
                            : "outside the air of the ";
            }
            throw Error("--scanner " + vec_text(s) + " is " + where + shape_name(o.shape.kind) +
                        " (signed distance " + num(sd) +
                        "): a scanner must be in the open (outside a solid, inside the room, off the plane)");
        }
    }
    if (o.threads > 4096) throw Error("--threads must be at most 4096, got " + std::to_string(o.threads));
}

namespace {

/// The scan pattern: every scanner's field and the scan lines, scanner by scanner.
void plan_lines(const ScanOptions& o, const Frame& frame, std::vector<Field>& fields,
                std::vector<Line>& lines) {
    double grid_rays = 0;
    for (std::uint32_t s = 0; s < o.scanners.size(); ++s) {
        fields.push_back(make_field(o, frame, o.scanners[s]));
        const Field& f = fields.back();
        const double nk = double(std::max<std::int64_t>(0, f.k1 - f.k0 + 1));
        const double nj = double(std::max<std::int64_t>(0, f.j1 - f.j0 + 1));
        grid_rays += nk * nj;
        if (nj > 0 && double(lines.size()) + nk > k_max_lines)
            throw Error("the scan pattern has more than " + num(k_max_lines) +
                        " scan lines: increase --line-step");
        if (grid_rays > k_max_rays)
            throw Error("the scan pattern has more than " + num(k_max_rays) +
                        " rays: increase --sample-step or --line-step");
        for (std::int64_t k = f.k0; k <= f.k1 && nj > 0; ++k) lines.push_back({s, k});
    }
}

/// Casts the rays of one scan line; its returns depend only on (seed, scanner, k).
struct LineCaster {
    const ScanOptions& o;
    const Frame& frame;
    const std::vector<Field>& fields;
    double sigma0;   ///< range noise sigma at range 0
    double cos_max;  ///< cosine of the largest incidence

    void operator()(const Line& line, LineCounts& c, std::vector<Return>& out) const {
        const Field& f = fields[line.scanner];
        const Vec3& origin = o.scanners[line.scanner];
        const double az = double(line.k) * o.line_step_degrees;
        for (std::int64_t j = f.j0; j <= f.j1; ++j) {
            const Vec3 d = frame.direction(az, double(j) * o.sample_step_degrees);
            if (!f.full && dot(d, f.toward) < f.cos_half) continue;  // misses the bounding sphere
            ++c.rays;
            const std::optional<RayHit> hit = first_hit(o.shape, origin, d);
            if (!hit) {
                ++c.misses;
                continue;
            }
            const double cos_i = std::fabs(dot(d, hit->normal));
            if (cos_i < cos_max) {
                ++c.grazing;
                continue;
            }
            Stream rs{hash(o.seed, k_stream_ray, line.scanner,
                           (std::uint64_t(std::uint32_t(line.k)) << 32) | std::uint32_t(j))};
            if (o.dropout > 0) {
                const double x = (1 - cos_i) / (1 - cos_max);
                if (rs.uniform() < o.dropout * x * x) {
                    ++c.dropout;
                    continue;
                }
            }
            Return r;
            r.point = hit->point;
            const double sigma = sigma0 + o.range_noise_per_range * hit->t;
            if (sigma > 0) r.point = add(r.point, mul(d, sigma * truncated_gaussian(rs)));
            r.normal = {float(hit->normal[0]), float(hit->normal[1]), float(hit->normal[2])};
            double intensity = albedo(o.shape, hit->part) * cos_i;
            if (o.intensity_noise > 0) intensity *= 1 + o.intensity_noise * truncated_gaussian(rs);
            r.intensity = float(std::max(0.0, intensity));
            r.part = static_cast<std::int8_t>(hit->part);
            out.push_back(r);
        }
    }
};

/// Per scanner: its field and the counts of its lines; returns the number of returns.
std::uint64_t tally_scanners(const ScanOptions& o, const std::vector<Field>& fields,
                             const std::vector<Line>& lines, const std::vector<LineCounts>& line_counts,
                             const std::vector<std::vector<Return>>& line_returns, ScanResult& result) {
    for (std::size_t s = 0; s < o.scanners.size(); ++s) {
        ScannerStats st;
        st.position = o.scanners[s];
        st.full_field = fields[s].full;
        st.azimuth_degrees[0] = fields[s].az[0];
        st.azimuth_degrees[1] = fields[s].az[1];
        st.elevation_degrees[0] = fields[s].el[0];
        st.elevation_degrees[1] = fields[s].el[1];
        result.scanners.push_back(st);
    }
    std::uint64_t n = 0;
    for (std::size_t li = 0; li < lines.size(); ++li) {
        ScannerStats& st = result.scanners[lines[li].scanner];
        const LineCounts& c = line_counts[li];
        st.lines += c.rays > 0;
        st.rays += c.rays;
        st.misses += c.misses;
        st.dropped_grazing += c.grazing;
        st.dropped_dropout += c.dropout;
        st.returns += line_returns[li].size();
        n += line_returns[li].size();
    }
    return n;
}

/// The returns as points, in (scanner, line, sample) order (the line arrays are freed); counts the
/// returns of each part into part_count. Returns the number of points written.
std::size_t store_returns(const ScanOptions& o, const std::vector<Line>& lines,
                          std::vector<std::vector<Return>>& line_returns,
                          std::vector<std::uint64_t>& part_count, ScanResult& result) {
    pre::PointCloud& cloud = result.cloud;
    const bool many = o.scanners.size() > 1;
    std::size_t i = 0;
    for (std::size_t li = 0; li < lines.size(); ++li) {
        const std::uint32_t s = lines[li].scanner;
        if (li == 0 || lines[li - 1].scanner != s) result.scanners[s].first = i;
        for (const Return& r : line_returns[li]) {
            cloud.positions[i] = r.point;
            cloud.intensities[i] = r.intensity;
            if (o.normals) cloud.normals[i] = r.normal;
            if (o.colors == ColorMode::normal)
                cloud.colors[i] = normal_color({r.normal.x, r.normal.y, r.normal.z});
            else if (o.colors != ColorMode::none)
                cloud.colors[i] = part_color(o, r.part);
            if (many) cloud.scan_ids[i] = static_cast<std::uint16_t>(s);
            result.part[i] = r.part;
            ++part_count[static_cast<std::size_t>(r.part)];
            ++i;
        }
        std::vector<Return>().swap(line_returns[li]);
    }
    return i;
}

/// Mixed-pixel outliers: k_out of the n returns moved along their ray. The choice is Floyd's
/// sampling of k distinct indices out of n (Bentley and Floyd, "A sample of brilliance", CACM
/// 1987), one seeded stream, so it is reproducible. Returns how many moved towards the scanner.
std::uint64_t displace_outliers(const ScanOptions& o, std::uint64_t n, std::uint64_t k_out, double size,
                                ScanResult& result) {
    pre::PointCloud& cloud = result.cloud;
    const bool many = o.scanners.size() > 1;
    {
        std::unordered_set<std::uint64_t> chosen;
        chosen.reserve(static_cast<std::size_t>(k_out));
        Stream pick{hash(o.seed, k_stream_outlier_pick, n)};
        for (std::uint64_t j = n - k_out; j < n; ++j) {
            const std::uint64_t t = std::min(j, static_cast<std::uint64_t>(pick.uniform() * double(j + 1)));
            if (!chosen.insert(t).second) chosen.insert(j);
        }
        result.outlier_indices.assign(chosen.begin(), chosen.end());
        std::sort(result.outlier_indices.begin(), result.outlier_indices.end());
    }
    std::uint64_t toward = 0;
    for (std::uint64_t idx : result.outlier_indices) {
        const Vec3& s = o.scanners[many ? cloud.scan_ids[idx] : 0];
        Vec3& p = cloud.positions[idx];
        const Vec3 ray = sub(p, s);
        const double range = length(ray);
        if (!(range > 0)) continue;
        Stream ds{hash(o.seed, k_stream_outlier_shift, idx)};
        const bool closer = ds.uniform() < 0.5;
        double shift = (k_outlier_min + (k_outlier_max - k_outlier_min) * ds.uniform()) * size;
        if (closer) {
            shift = -std::min(shift, (1 - k_outlier_keep_range) * range);
            ++toward;
        }
        p = add(p, mul(ray, shift / range));
    }
    return toward;
}

/// Uniform outliers: n_uniform points in the box lo..hi, appended from index `first`.
void append_uniform_outliers(const ScanOptions& o, std::uint64_t n_uniform, std::size_t first, const Vec3& lo,
                             const Vec3& hi, ScanResult& result) {
    pre::PointCloud& cloud = result.cloud;
    const bool many = o.scanners.size() > 1;
    std::size_t i = first;
    for (std::uint64_t u = 0; u < n_uniform; ++u, ++i) {
        Stream us{hash(o.seed, k_stream_uniform, u)};
        Vec3 p;
        for (int a = 0; a < 3; ++a) p[a] = lo[a] + (hi[a] - lo[a]) * us.uniform();
        cloud.positions[i] = p;
        cloud.intensities[i] = float(us.uniform());
        const Vec3 nrm =
            (o.normals || o.colors == ColorMode::normal) ? closest(o.shape, p).normal : Vec3{0, 1, 0};
        if (o.normals) cloud.normals[i] = {float(nrm[0]), float(nrm[1]), float(nrm[2])};
        if (o.colors == ColorMode::normal)
            cloud.colors[i] = normal_color(nrm);
        else if (o.colors == ColorMode::parts)
            cloud.colors[i] = {128, 128, 128, 255};
        else if (o.colors == ColorMode::constant)
            cloud.colors[i] = o.color;
        if (many) cloud.scan_ids[i] = static_cast<std::uint16_t>(u % o.scanners.size());
        result.part[i] = -1;
    }
}

/// What the provenance records of the outliers.
struct OutlierRecord {
    std::uint64_t count = 0, toward = 0;  ///< mixed-pixel outliers, and those moved closer
    Vec3 lo{}, hi{};                      ///< the uniform outliers' box
};

/// The scan's provenance parameters (JSON).
std::string scan_parameters(const ScanOptions& o, const Frame& frame, double sigma0, const OutlierRecord& out,
                            const ScanResult& result) {
    nlohmann::ordered_json j;
    j["shape"] = nlohmann::ordered_json::parse(shape_to_json(o.shape));
    j["mode"] = "scan";
    j["pattern"] = {{"kind", "terrestrial laser scanner: vertical scan lines at azimuth steps"},
                    {"axis", frame.a},
                    {"azimuth_zero", frame.e1},
                    {"sample_step_degrees", o.sample_step_degrees},
                    {"line_step_degrees", o.line_step_degrees},
                    {"anisotropy", o.line_step_degrees / o.sample_step_degrees},
                    {"blind_cone_degrees", o.blind_cone_degrees}};
    j["max_incidence_degrees"] = o.max_incidence_degrees;
    j["dropout"] = o.dropout;
    j["dropout_model"] = "dropout * ((1 - cos i) / (1 - cos max_incidence))^2";
    j["range_noise"] = o.range_noise;
    j["range_noise_per_range"] = o.range_noise_per_range;
    j["range_noise_sigma"] = sigma0;
    j["noise_truncation"] = k_noise_truncation;
    j["intensity_model"] = "albedo(part) * cos(incidence) * (1 + intensity_noise * g), clamped >= 0";
    j["intensity_noise"] = o.intensity_noise;
    j["normals"] = o.normals;
    j["colors"] = color_mode_name(o.colors);
    j["seed"] = o.seed;
    nlohmann::ordered_json js = nlohmann::ordered_json::array();
    std::uint64_t rays = 0, misses = 0, grazing = 0, dropout = 0;
    for (const ScannerStats& st : result.scanners) {
        nlohmann::ordered_json e;
        e["position"] = st.position;
        e["field"] = st.full_field ? "full sphere minus the blind cone" : "bounding-sphere cone";
        e["azimuth_degrees"] = {st.azimuth_degrees[0], st.azimuth_degrees[1]};
        e["elevation_degrees"] = {st.elevation_degrees[0], st.elevation_degrees[1]};
        e["lines"] = st.lines;
        e["rays"] = st.rays;
        e["misses"] = st.misses;
        e["dropped_grazing"] = st.dropped_grazing;
        e["dropped_dropout"] = st.dropped_dropout;
        e["returns"] = st.returns;
        e["first"] = st.first;
        js.push_back(e);
        rays += st.rays;
        misses += st.misses;
        grazing += st.dropped_grazing;
        dropout += st.dropped_dropout;
    }
    j["scanners"] = js;
    j["rays"] = rays;
    j["misses"] = misses;
    j["dropped_grazing"] = grazing;
    j["dropped_dropout"] = dropout;
    j["returns"] = result.returns;
    nlohmann::ordered_json jo;
    jo["fraction"] = o.outliers;
    jo["displacement"] = {k_outlier_min, k_outlier_max};
    jo["displacement_unit"] = "model size, along the ray, either sign";
    jo["count"] = out.count;
    jo["toward_scanner"] = out.toward;
    if (out.count <= k_max_recorded_outliers) jo["indices"] = result.outlier_indices;
    j["outliers"] = jo;
    nlohmann::ordered_json ju;
    ju["fraction"] = o.uniform_outliers;
    ju["box"] = {out.lo, out.hi};
    ju["first"] = result.uniform_first;
    ju["count"] = result.uniform_count;
    j["uniform_outliers"] = ju;
    j["points"] = result.returns + result.uniform_count;
    nlohmann::ordered_json jp = nlohmann::ordered_json::array();
    for (const PartRange& p : result.parts) jp.push_back({{"name", p.name}, {"returns", p.count}});
    j["parts"] = jp;
    return j.dump();
}

}  // namespace

ScanResult scan(const ScanOptions& options,
                const std::function<void(std::uint64_t, std::uint64_t)>& progress) {
    ScanOptions o = options;
    if (o.scanners.empty()) o.scanners = default_scanners(o.shape, 1);
    validate(o);
    const Frame frame(o.axis);
    const double size = shape_size(o.shape);
    const double sigma0 = o.range_noise * size;
    const double cos_max = std::cos(o.max_incidence_degrees * k_deg);
    const std::vector<std::string> names = part_names(o.shape);

    std::vector<Field> fields;
    std::vector<Line> lines;
    plan_lines(o, frame, fields, lines);

    // Cast every line.
    std::vector<std::vector<Return>> line_returns(lines.size());
    std::vector<LineCounts> line_counts(lines.size());
    const LineCaster cast{o, frame, fields, sigma0, cos_max};
    constexpr std::size_t k_chunk = 8;  // lines per work item
    std::atomic<std::size_t> done{0};
    // The calling thread (worker 0) is the only one that reports progress.
    parallel_chunks(lines.size(), k_chunk, resolve_threads(o.threads),
                    [&](std::size_t begin, std::size_t end, unsigned worker) {
                        for (std::size_t li = begin; li < end; ++li)
                            cast(lines[li], line_counts[li], line_returns[li]);
                        const std::size_t total_done = done.fetch_add(end - begin) + (end - begin);
                        if (worker == 0 && progress) progress(total_done, lines.size());
                    });
    if (progress) progress(lines.size(), lines.size());

    // Gather in (scanner, line, sample) order.
    ScanResult result;
    result.range_sigma = sigma0;
    const std::uint64_t n = tally_scanners(o, fields, lines, line_counts, line_returns, result);
    if (n == 0)
        throw Error("the scan has no returns (every ray missed the " + std::string(shape_name(o.shape.kind)) +
                    " or was dropped): check --scanner, --max-incidence and --dropout");
    const std::uint64_t n_uniform = static_cast<std::uint64_t>(std::llround(o.uniform_outliers * double(n)));
    if (n + n_uniform > k_max_points)
        throw Error("the scan has " + std::to_string(n + n_uniform) + " points, more than a pool holds (" +
                    std::to_string(k_max_points) + "): increase --sample-step or --line-step");
    result.returns = n;
    const std::size_t total = static_cast<std::size_t>(n + n_uniform);

    pre::PointCloud& cloud = result.cloud;
    cloud.flags = pool::k_model_synthetic;
    cloud.positions.resize(total);
    cloud.intensities.resize(total);
    if (o.normals) cloud.normals.resize(total);
    if (o.colors != ColorMode::none) cloud.colors.resize(total);
    if (o.scanners.size() > 1) cloud.scan_ids.resize(total);
    result.part.resize(total);
    for (const Vec3& s : o.scanners)
        cloud.sensors.push_back(pool::Sensor{{s[0], s[1], s[2]}, pool::k_sensor_point, 0});
    std::vector<std::uint64_t> part_count(names.size(), 0);
    const std::size_t stored = store_returns(o, lines, line_returns, part_count, result);

    OutlierRecord record;
    record.count = static_cast<std::uint64_t>(std::llround(o.outliers * double(n)));
    record.toward = displace_outliers(o, n, record.count, size, result);

    result.uniform_first = n;
    result.uniform_count = n_uniform;
    const auto box = shape_bounds(o.shape);
    for (int a = 0; a < 3; ++a) {
        record.lo[a] = box[0][a] - k_uniform_margin * size;
        record.hi[a] = box[1][a] + k_uniform_margin * size;
    }
    append_uniform_outliers(o, n_uniform, stored, record.lo, record.hi, result);

    for (std::size_t p = 0; p < names.size(); ++p) {
        PartRange r;
        r.name = names[p];
        r.count = part_count[p];
        r.color = part_color(o, int(p));
        result.parts.push_back(r);
    }
    result.parameters_json = scan_parameters(o, frame, sigma0, record, result);
    return result;
}

}  // namespace prt::synth
