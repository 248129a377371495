#include "poses.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "prt/error.h"
#include "quote.h"

namespace prt::pre::import {

namespace {

namespace fs = std::filesystem;

std::string read_text(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error(path.string() + ": cannot open: " + std::strerror(errno));
    std::ostringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

std::vector<std::string_view> words_of(std::string_view line) {
    std::vector<std::string_view> out;
    std::size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) ++i;
        const std::size_t b = i;
        while (i < line.size() && !std::isspace(static_cast<unsigned char>(line[i]))) ++i;
        if (i > b) out.push_back(line.substr(b, i - b));
    }
    return out;
}

/// A number of the text, or an error naming it ("nan" and "inf" parse, and are refused as not finite).
double number(std::string_view word, const std::string& where, const char* what) {
    const char* b = word.data();
    const char* e = b + word.size();
    if (b < e && *b == '+') ++b;
    double v = 0;
    const auto [p, ec] = std::from_chars(b, e, v);
    if (ec == std::errc::result_out_of_range)
        throw Error(where + ": " + what + " " + quoted(word) + " is out of range");
    if (ec != std::errc() || p != e)
        throw Error(where + ": " + what + " " + quoted(word) + " is not a number");
    if (!std::isfinite(v)) throw Error(where + ": " + what + " " + quoted(word) + " is not finite");
    return v;
}

/// Checks the norm of a quaternion and returns its rotation.
Rigid checked_quaternion(double w, double x, double y, double z, const std::string& where) {
    const double norm = std::sqrt(w * w + x * x + y * y + z * z);
    if (!std::isfinite(norm)) throw Error(where + ": the quaternion is not finite");
    if (std::fabs(norm - 1.0) > k_quaternion_tolerance) {
        char buf[160];
        std::snprintf(buf, sizeof buf, ": the quaternion has norm %.6g, not 1 (within %g)", norm,
                      k_quaternion_tolerance);
        throw Error(where + buf);
    }
    return rotation_from_quaternion(w, x, y, z);
}

fs::path resolve(const fs::path& pose_file, const std::string& file) {
    const fs::path f(file);
    return f.is_absolute() ? f : pose_file.parent_path() / f;
}

void require_file(const fs::path& file, const std::string& where) {
    std::error_code ec;
    if (!fs::is_regular_file(file, ec))
        throw Error(where + ": scan file " + quoted(std::string_view(file.string()), 200) +
                    (fs::exists(file, ec) ? " is not a regular file" : " not found"));
}

// ---- Stanford .conf ------------------------------------------------------------------------------

std::vector<PoseEntry> read_conf(const fs::path& path, const std::string& text) {
    const std::string label = path.string();
    std::vector<PoseEntry> out;
    std::size_t pos = 0, line_no = 0;
    while (pos < text.size()) {
        std::size_t eol = text.find('\n', pos);
        if (eol == std::string::npos) eol = text.size();
        const std::string_view line(text.data() + pos, eol - pos);
        pos = eol + 1;
        ++line_no;
        const std::string where = label + ": line " + std::to_string(line_no);
        if (line.find('\0') != std::string_view::npos)
            throw Error(where + ": binary bytes (not a .conf file)");
        const auto w = words_of(line);
        if (w.empty() || w[0][0] == '#') continue;
        if (w[0] == "camera") continue;  // the viewer's camera of scanalyze: not a scan
        if (w[0] != "bmesh")
            throw Error(where + ": unknown keyword " + quoted(w[0]) + " (expected bmesh or camera)");
        if (w.size() != 9)
            throw Error(where + ": bmesh needs FILE tx ty tz qi qj qk qr (8 fields after bmesh), got " +
                        std::to_string(w.size() - 1));
        PoseEntry e;
        e.where = where;
        e.file = resolve(path, std::string(w[1]));
        double v[7];
        static const char* k_names[] = {"tx", "ty", "tz", "qi", "qj", "qk", "qr"};
        for (int i = 0; i < 7; ++i) v[i] = number(w[2 + i], where, k_names[i]);
        // p_merged = R(q)^-1 p + t with q = (qi, qj, qk, qr), scalar last (checked against
        // bun_zipper.ply by tests/preprocess/import/poses_test.cpp): R(q)^-1 is R of the conjugate.
        const Rigid rq = checked_quaternion(v[6], v[3], v[4], v[5], where);
        for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b) e.pose.r[a][b] = rq.r[b][a];
        for (int a = 0; a < 3; ++a) e.pose.t[a] = v[a];
        // The scanner sits far away on the +z side of the scan's own frame (a direction sensor).
        e.sensor_given = true;
        e.sensor = pool::Sensor{{0.0, 0.0, 1.0}, pool::k_sensor_direction, 0};
        require_file(e.file, where);
        out.push_back(std::move(e));
    }
    if (out.empty()) throw Error(label + ": no bmesh line (no scan to import)");
    return out;
}

// ---- JSON ----------------------------------------------------------------------------------------

std::array<double, 3> vector3(const nlohmann::json& j, const std::string& where, const char* what) {
    if (!j.is_array() || j.size() != 3)
        throw Error(where + ": " + what + " must be an array of 3 numbers" +
                    (j.is_array() ? ", got " + std::to_string(j.size()) : std::string()));
    std::array<double, 3> v{};
    for (int i = 0; i < 3; ++i) {
        if (!j[i].is_number())
            throw Error(where + ": " + what + "[" + std::to_string(i) + "] is not a number");
        v[i] = j[i].get<double>();
        if (!std::isfinite(v[i]))
            throw Error(where + ": " + what + "[" + std::to_string(i) + "] is not finite");
    }
    return v;
}

Rigid matrix_pose(const nlohmann::json& j, const std::string& where) {
    if (!j.is_array()) throw Error(where + ": matrix must be an array of 16 numbers (4x4, row-major)");
    if (j.size() != 16)
        throw Error(where + ": matrix has " + std::to_string(j.size()) +
                    " numbers, expected 16 (4x4, row-major)");
    double m[16];
    for (int i = 0; i < 16; ++i) {
        if (!j[i].is_number()) throw Error(where + ": matrix[" + std::to_string(i) + "] is not a number");
        m[i] = j[i].get<double>();
        if (!std::isfinite(m[i])) throw Error(where + ": matrix[" + std::to_string(i) + "] is not finite");
    }
    char buf[200];
    if (std::fabs(m[12]) > k_rigid_tolerance || std::fabs(m[13]) > k_rigid_tolerance ||
        std::fabs(m[14]) > k_rigid_tolerance || std::fabs(m[15] - 1.0) > k_rigid_tolerance) {
        std::snprintf(buf, sizeof buf,
                      ": matrix's last row is %g %g %g %g, expected 0 0 0 1 (a rigid transform)", m[12],
                      m[13], m[14], m[15]);
        throw Error(where + buf);
    }
    Rigid r;
    for (int a = 0; a < 3; ++a) {
        for (int b = 0; b < 3; ++b) r.r[a][b] = m[4 * a + b];
        r.t[a] = m[4 * a + 3];
    }
    double worst = 0;
    for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) {
            double d = 0;
            for (int c = 0; c < 3; ++c) d += r.r[c][a] * r.r[c][b];
            worst = std::max(worst, std::fabs(d - (a == b ? 1.0 : 0.0)));
        }
    if (worst > k_rigid_tolerance) {
        std::snprintf(buf, sizeof buf,
                      ": matrix is not rigid (R^T R differs from I by %.3g > %g: scale or shear; write "
                      "rotations with at least 8 significant digits)",
                      worst, k_rigid_tolerance);
        throw Error(where + buf);
    }
    const double det = r.r[0][0] * (r.r[1][1] * r.r[2][2] - r.r[1][2] * r.r[2][1]) -
                       r.r[0][1] * (r.r[1][0] * r.r[2][2] - r.r[1][2] * r.r[2][0]) +
                       r.r[0][2] * (r.r[1][0] * r.r[2][1] - r.r[1][1] * r.r[2][0]);
    if (std::fabs(det - 1.0) > k_rigid_tolerance) {
        std::snprintf(buf, sizeof buf,
                      ": matrix has determinant %.6g, not +1 (a reflection is not a rigid motion)", det);
        throw Error(where + buf);
    }
    return r;
}

std::vector<PoseEntry> read_json(const fs::path& path, const std::string& text) {
    const std::string label = path.string();
    nlohmann::json root;
    try {
        root = nlohmann::json::parse(text);
    } catch (const nlohmann::json::parse_error& e) {
        // Byte offset -> line number for the one-line message.
        const std::size_t at = std::min<std::size_t>(e.byte, text.size());
        const std::size_t line = 1 + static_cast<std::size_t>(std::count(
                                         text.begin(), text.begin() + static_cast<std::ptrdiff_t>(at), '\n'));
        throw Error(label + ": line " + std::to_string(line) + ": invalid JSON (" +
                    std::string(e.what()).substr(0, 160) + ")");
    } catch (const nlohmann::json::exception& e) {  // e.g. a number too large for a double
        throw Error(label + ": invalid JSON (" + std::string(e.what()).substr(0, 160) + ")");
    }
    if (!root.is_object()) throw Error(label + ": expected a JSON object {\"scans\": [...]}");
    for (const auto& [key, value] : root.items())
        if (key != "scans" && key != "comment")
            throw Error(label + ": unknown key " + quoted(std::string_view(key)) +
                        " (expected \"scans\", \"comment\")");
    const auto scans = root.find("scans");
    if (scans == root.end() || !scans->is_array()) throw Error(label + ": \"scans\" must be an array");
    if (scans->empty()) throw Error(label + ": \"scans\" is empty (no scan to import)");
    std::vector<PoseEntry> out;
    for (std::size_t i = 0; i < scans->size(); ++i) {
        const nlohmann::json& s = (*scans)[i];
        const std::string where = label + ": scans[" + std::to_string(i) + "]";
        if (!s.is_object()) throw Error(where + ": expected an object {\"file\": ...}");
        for (const auto& [key, value] : s.items())
            if (key != "file" && key != "matrix" && key != "translation" && key != "quaternion" &&
                key != "sensor" && key != "comment")
                throw Error(where + ": unknown key " + quoted(std::string_view(key)) +
                            " (file, matrix, translation, quaternion, sensor, comment)");
        PoseEntry e;
        e.where = where;
        const auto file = s.find("file");
        if (file == s.end() || !file->is_string() || file->get<std::string>().empty())
            throw Error(where + ": \"file\" must be a non-empty string");
        e.file = resolve(path, file->get<std::string>());
        const bool has_matrix = s.contains("matrix");
        const bool has_tq = s.contains("translation") || s.contains("quaternion");
        if (has_matrix && has_tq)
            throw Error(where + ": give either \"matrix\" or \"translation\"/\"quaternion\", not both");
        if (has_matrix) e.pose = matrix_pose(s["matrix"], where);
        if (s.contains("quaternion")) {
            const nlohmann::json& q = s["quaternion"];
            if (!q.is_object() || q.size() != 4 || !q.contains("w") || !q.contains("x") || !q.contains("y") ||
                !q.contains("z"))
                throw Error(where + ": quaternion must be {\"w\": .., \"x\": .., \"y\": .., \"z\": ..}");
            double c[4];
            const char* names[] = {"w", "x", "y", "z"};
            for (int k = 0; k < 4; ++k) {
                if (!q[names[k]].is_number())
                    throw Error(where + ": quaternion." + names[k] + " is not a number");
                c[k] = q[names[k]].get<double>();
                if (!std::isfinite(c[k])) throw Error(where + ": quaternion." + names[k] + " is not finite");
            }
            e.pose = checked_quaternion(c[0], c[1], c[2], c[3], where);
        }
        if (s.contains("translation")) {
            const auto t = vector3(s["translation"], where, "translation");
            for (int a = 0; a < 3; ++a) e.pose.t[a] = t[a];
        }
        if (s.contains("sensor")) {
            e.sensor_given = true;
            const nlohmann::json& js = s["sensor"];
            if (!js.is_null()) {
                if (!js.is_object() || js.size() != 1 || (!js.contains("point") && !js.contains("direction")))
                    throw Error(
                        where +
                        ": sensor must be {\"point\": [x, y, z]}, {\"direction\": [x, y, z]} or null");
                pool::Sensor sensor{};
                if (js.contains("point")) {
                    const auto p = vector3(js["point"], where, "sensor.point");
                    std::copy(p.begin(), p.end(), sensor.position);
                    sensor.kind = pool::k_sensor_point;
                } else {
                    const auto d = vector3(js["direction"], where, "sensor.direction");
                    const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
                    if (!(len > 0)) throw Error(where + ": sensor.direction is zero");
                    for (int a = 0; a < 3; ++a) sensor.position[a] = d[a] / len;
                    sensor.kind = pool::k_sensor_direction;
                }
                e.sensor = sensor;
            }
        }
        require_file(e.file, where);
        out.push_back(std::move(e));
    }
    return out;
}

}  // namespace

pool::Sensor Rigid::apply(const pool::Sensor& s) const {
    pool::Sensor out = s;
    const std::array<double, 3> v{s.position[0], s.position[1], s.position[2]};
    const auto w = s.kind == pool::k_sensor_direction ? rotate(v) : apply(v);
    if (s.kind == pool::k_sensor_direction) {
        // Renormalise: a rotation keeps the length up to rounding, the pool checks it to 1e-6.
        const double len = std::sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
        for (int a = 0; a < 3; ++a) out.position[a] = w[a] / len;
    } else {
        for (int a = 0; a < 3; ++a) out.position[a] = w[a];
    }
    return out;
}

bool Rigid::is_identity() const {
    for (int a = 0; a < 3; ++a) {
        if (t[a] != 0.0) return false;
        for (int b = 0; b < 3; ++b)
            if (r[a][b] != (a == b ? 1.0 : 0.0)) return false;
    }
    return true;
}

Rigid rotation_from_quaternion(double w, double x, double y, double z) {
    const double n = std::sqrt(w * w + x * x + y * y + z * z);
    w /= n;
    x /= n;
    y /= n;
    z /= n;
    Rigid r;
    r.r[0][0] = 1 - 2 * (y * y + z * z);
    r.r[0][1] = 2 * (x * y - w * z);
    r.r[0][2] = 2 * (x * z + w * y);
    r.r[1][0] = 2 * (x * y + w * z);
    r.r[1][1] = 1 - 2 * (x * x + z * z);
    r.r[1][2] = 2 * (y * z - w * x);
    r.r[2][0] = 2 * (x * z - w * y);
    r.r[2][1] = 2 * (y * z + w * x);
    r.r[2][2] = 1 - 2 * (x * x + y * y);
    return r;
}

std::vector<PoseEntry> read_poses(const fs::path& path) {
    const std::string text = read_text(path);
    std::string ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    if (ext == ".conf") return read_conf(path, text);
    if (ext == ".json") return read_json(path, text);
    const std::size_t first = text.find_first_not_of(" \t\r\n");
    if (first == std::string::npos) throw Error(path.string() + ": pose file is empty");
    return text[first] == '{' ? read_json(path, text) : read_conf(path, text);
}

std::vector<PoseEntry> read_poses(const fs::path& path, const std::vector<fs::path>& only) {
    std::vector<PoseEntry> entries = read_poses(path);
    if (only.empty()) return entries;
    std::vector<PoseEntry> chosen;
    for (const fs::path& want : only) {
        std::error_code ec;
        const fs::path a = fs::weakly_canonical(want, ec);
        auto it = std::find_if(entries.begin(), entries.end(), [&](const PoseEntry& e) {
            std::error_code ec2;
            return fs::weakly_canonical(e.file, ec2) == a;
        });
        if (it == entries.end())
            throw Error(want.string() + ": not listed in the pose file " + path.string());
        chosen.push_back(*it);
    }
    return chosen;
}

}  // namespace prt::pre::import
