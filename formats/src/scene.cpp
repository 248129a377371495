// PointRT scene description: a strict JSON reader and writer for the structs in prt/formats/scene.h.
// Every key, type, default and range is documented in formats/SCENE.md; keep the two in step.
//
// Strictness: unknown keys, duplicate keys, wrong types, non-integral integers and out-of-range
// values are errors. Every error is one line "LABEL: /json/pointer: what is wrong" (RFC 6901
// pointer to the offending value), so a user can find it in the file.
#include "prt/formats/scene.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <initializer_list>
#include <limits>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <utility>

#include "prt/vec3.h"

namespace prt::scene {
namespace {

using Json = nlohmann::json;

// ---- Limits (documented in SCENE.md) -------------------------------------------------------------
constexpr std::uint32_t k_max_resolution = 16384;
constexpr std::uint32_t k_max_area_samples = 64;  // per edge: 64 x 64 = 4096 shadow rays per hit
constexpr std::uint32_t k_max_bounces = 64;
constexpr std::uint32_t k_max_spp = 65536;
constexpr double k_fraction_sum_tolerance = 1e-6;

/// RFC 6901: "~" -> "~0", "/" -> "~1".
std::string pointer_token(const std::string& key) {
    std::string out;
    out.reserve(key.size());
    for (char c : key) {
        if (c == '~')
            out += "~0";
        else if (c == '/')
            out += "~1";
        else
            out += c;
    }
    return out;
}

std::string join(const std::string& path, const std::string& key) {
    return path + "/" + pointer_token(key);
}
std::string join(const std::string& path, std::size_t index) {
    return path + "/" + std::to_string(index);
}

std::string type_name(const Json& j) {
    switch (j.type()) {
        case Json::value_t::null:
            return "null";
        case Json::value_t::object:
            return "an object";
        case Json::value_t::array:
            return "an array";
        case Json::value_t::string:
            return "a string";
        case Json::value_t::boolean:
            return "a boolean";
        case Json::value_t::number_integer:
        case Json::value_t::number_unsigned:
            return "an integer";
        case Json::value_t::number_float:
            return "a number with a fraction";
        default:
            return "an unsupported value";
    }
}

std::string format_number(double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.17g", v);
    // Prefer the short form when it reads back exactly (0.1 rather than 0.10000000000000001).
    char shorter[64];
    std::snprintf(shorter, sizeof shorter, "%g", v);
    return std::strtod(shorter, nullptr) == v ? std::string(shorter) : std::string(buf);
}

/// An error message kept on one line: control characters from the document (a key or name
/// holding "\n" or "\r") are written as JSON escapes, \u000a.
std::string one_line(const std::string& text) {
    std::string out;
    out.reserve(text.size());
    for (const char c : text) {
        const auto u = static_cast<unsigned char>(c);
        if (u < 0x20 || u == 0x7F) {
            char buf[8];
            std::snprintf(buf, sizeof buf, "\\u%04x", u);
            out += buf;
        } else {
            out += c;
        }
    }
    return out;
}

/// Error reporting and path resolution shared by all readers of one document.
struct Context {
    std::string label;
    std::filesystem::path base_dir;

    [[noreturn]] void fail(const std::string& path, const std::string& what) const {
        throw Error(one_line(label + ": " + (path.empty() ? std::string("(document)") : path) + ": " + what));
    }
};

/// Checked access to one JSON object: rejects anything but an object, and unknown keys.
class ObjectReader {
public:
    ObjectReader(const Context& ctx, const Json& j, std::string path, std::initializer_list<const char*> keys)
        : m_ctx(ctx), m_json(j), m_path(std::move(path)) {
        if (!j.is_object()) ctx.fail(m_path, "expected an object, got " + type_name(j));
        for (const auto& [key, value] : j.items()) {
            bool known = false;
            for (const char* k : keys) known = known || key == k;
            if (!known) {
                std::string allowed;
                for (const char* k : keys) allowed += (allowed.empty() ? "" : ", ") + std::string(k);
                ctx.fail(join(m_path, key), "unknown key (allowed here: " + allowed + ")");
            }
        }
    }

    /// The value of `key`, or nullptr when absent.
    const Json* find(const char* key) const {
        auto it = m_json.find(key);
        return it == m_json.end() ? nullptr : &*it;
    }
    std::string path(const char* key) const { return join(m_path, key); }
    const std::string& path() const { return m_path; }
    const Context& ctx() const { return m_ctx; }

    // Typed optional reads: leave `out` untouched when the key is absent.
    bool number(const char* key, double& out) const {
        const Json* j = find(key);
        if (!j) return false;
        if (!j->is_number()) m_ctx.fail(path(key), "expected a number, got " + type_name(*j));
        const double v = j->get<double>();
        if (!std::isfinite(v)) m_ctx.fail(path(key), "expected a finite number");
        out = v;
        return true;
    }
    bool number(const char* key, float& out) const {
        double v = 0;
        if (!number(key, v)) return false;
        if (std::fabs(v) > std::numeric_limits<float>::max())
            m_ctx.fail(path(key), format_number(v) + " does not fit a 32-bit float");
        out = static_cast<float>(v);
        return true;
    }
    bool integer(const char* key, std::uint32_t& out, std::uint32_t lo, std::uint32_t hi) const {
        const Json* j = find(key);
        if (!j) return false;
        if (j->is_number_float())
            m_ctx.fail(path(key), "expected an integer, got " + format_number(j->get<double>()));
        if (!j->is_number_integer()) m_ctx.fail(path(key), "expected an integer, got " + type_name(*j));
        const bool negative = j->is_number_unsigned() ? false : j->get<std::int64_t>() < 0;
        const std::uint64_t v = negative ? 0 : j->get<std::uint64_t>();
        if (negative || v < lo || v > hi) {
            const std::string got = negative ? std::to_string(j->get<std::int64_t>()) : std::to_string(v);
            m_ctx.fail(path(key), "must be an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) +
                                      "], got " + got);
        }
        out = static_cast<std::uint32_t>(v);
        return true;
    }
    bool boolean(const char* key, bool& out) const {
        const Json* j = find(key);
        if (!j) return false;
        if (!j->is_boolean()) m_ctx.fail(path(key), "expected true or false, got " + type_name(*j));
        out = j->get<bool>();
        return true;
    }
    bool string(const char* key, std::string& out) const {
        const Json* j = find(key);
        if (!j) return false;
        if (!j->is_string()) m_ctx.fail(path(key), "expected a string, got " + type_name(*j));
        out = j->get<std::string>();
        return true;
    }
    /// A file path: a non-empty string, resolved against the scene's folder when relative.
    bool file(const char* key, std::filesystem::path& out) const {
        std::string s;
        if (!string(key, s)) return false;
        if (s.empty()) m_ctx.fail(path(key), "expected a file path, got an empty string");
        std::filesystem::path p(s);
        if (p.is_relative() && !m_ctx.base_dir.empty()) p = (m_ctx.base_dir / p).lexically_normal();
        out = p;
        return true;
    }
    /// The array of 3 at `key` (null when absent); fails naming `form` ("[x, y, z]") otherwise.
    const Json* triple(const char* key, const char* form) const {
        const Json* j = find(key);
        if (j && (!j->is_array() || j->size() != 3))
            m_ctx.fail(path(key),
                       std::string("expected ") + form + " (an array of 3 numbers), got " +
                           (j->is_array() ? "an array of " + std::to_string(j->size()) : type_name(*j)));
        return j;
    }
    /// [x, y, z] of finite numbers.
    bool vec3(const char* key, Vec3& out) const {
        const Json* j = triple(key, "[x, y, z]");
        if (!j) return false;
        for (std::size_t i = 0; i < 3; ++i) {
            const Json& e = (*j)[i];
            if (!e.is_number()) m_ctx.fail(join(path(key), i), "expected a number, got " + type_name(e));
            out[i] = e.get<double>();
            if (!std::isfinite(out[i])) m_ctx.fail(join(path(key), i), "expected a finite number");
        }
        return true;
    }
    /// [r, g, b], each in [0, hi] (hi = infinity for light and background colors).
    bool color(const char* key, Color& out, double hi) const {
        const Json* j = triple(key, "[r, g, b]");
        if (!j) return false;
        for (std::size_t i = 0; i < 3; ++i) {
            const Json& e = (*j)[i];
            const std::string p = join(path(key), i);
            if (!e.is_number()) m_ctx.fail(p, "expected a number, got " + type_name(e));
            const double v = e.get<double>();
            if (!std::isfinite(v) || v < 0 || v > hi || v > std::numeric_limits<float>::max())
                m_ctx.fail(p, std::isinf(hi)
                                  ? "must be a finite number >= 0, got " + format_number(v)
                                  : "must be in [0, " + format_number(hi) + "], got " + format_number(v));
            out[i] = static_cast<float>(v);
        }
        return true;
    }

    // Range checks on values already read (the value is named by its key's path).
    void require_positive(const char* key, double v) const {
        if (!(v > 0)) m_ctx.fail(path(key), "must be > 0, got " + format_number(v));
    }
    void require_non_negative(const char* key, double v) const {
        if (!(v >= 0)) m_ctx.fail(path(key), "must be >= 0, got " + format_number(v));
    }
    void require_unit_interval(const char* key, double v) const {
        if (!(v >= 0 && v <= 1)) m_ctx.fail(path(key), "must be in [0, 1], got " + format_number(v));
    }

private:
    const Context& m_ctx;
    const Json& m_json;
    std::string m_path;
};

/// True when a and b (both non-zero) are parallel to within ~1e-6 radians.
bool parallel(const Vec3& a, const Vec3& b) {
    return length(cross(a, b)) <= 1e-6 * length(a) * length(b);
}

Camera parse_camera(const Context& ctx, const Json& j, const std::string& path) {
    ObjectReader r(ctx, j, path, {"position", "look_at", "up", "fov_y_degrees", "width", "height"});
    Camera c;
    r.vec3("position", c.position);
    r.vec3("look_at", c.look_at);
    r.vec3("up", c.up);
    if (r.number("fov_y_degrees", c.fov_y_degrees) && !(c.fov_y_degrees > 0 && c.fov_y_degrees < 180))
        ctx.fail(r.path("fov_y_degrees"),
                 "must be in (0, 180) degrees, got " + format_number(c.fov_y_degrees));
    r.integer("width", c.width, 1, k_max_resolution);
    r.integer("height", c.height, 1, k_max_resolution);
    const Vec3 view = sub(c.look_at, c.position);
    if (length(view) == 0) ctx.fail(r.path("look_at"), "equals the camera position (no view direction)");
    if (length(c.up) == 0) ctx.fail(r.path("up"), "must not be the zero vector");
    if (parallel(view, c.up))
        ctx.fail(r.path("up"), "is parallel to the view direction (look_at - position)");
    return c;
}

PointLight parse_point_light(const ObjectReader& r) {
    PointLight l;
    r.vec3("position", l.position);
    r.color("color", l.color, std::numeric_limits<double>::infinity());
    if (r.number("intensity", l.intensity)) r.require_non_negative("intensity", l.intensity);
    r.boolean("casts_shadows", l.casts_shadows);
    return l;
}

AreaLight parse_area_light(const ObjectReader& r) {
    AreaLight l;
    r.vec3("corner", l.corner);
    r.vec3("edge_u", l.edge_u);
    r.vec3("edge_v", l.edge_v);
    r.color("color", l.color, std::numeric_limits<double>::infinity());
    if (r.number("intensity", l.intensity)) r.require_non_negative("intensity", l.intensity);
    r.integer("samples", l.samples, 1, k_max_area_samples);
    r.boolean("casts_shadows", l.casts_shadows);
    if (length(l.edge_u) == 0) r.ctx().fail(r.path("edge_u"), "must not be the zero vector");
    if (length(l.edge_v) == 0) r.ctx().fail(r.path("edge_v"), "must not be the zero vector");
    if (parallel(l.edge_u, l.edge_v))
        r.ctx().fail(r.path("edge_v"), "is parallel to edge_u (the light would have no area)");
    return l;
}

void parse_lights(const Context& ctx, const Json& j, const std::string& path, Scene& scene) {
    if (!j.is_array()) ctx.fail(path, "expected an array of lights, got " + type_name(j));
    for (std::size_t i = 0; i < j.size(); ++i) {
        const std::string p = join(path, i);
        const Json& l = j[i];
        if (!l.is_object()) ctx.fail(p, "expected a light object, got " + type_name(l));
        auto type = l.find("type");
        if (type == l.end()) ctx.fail(p, "missing key \"type\" (\"point\" or \"area\")");
        if (!type->is_string()) ctx.fail(join(p, "type"), "expected a string, got " + type_name(*type));
        const std::string t = type->get<std::string>();
        if (t == "point") {
            ObjectReader r(ctx, l, p, {"type", "position", "color", "intensity", "casts_shadows"});
            scene.point_lights.push_back(parse_point_light(r));
        } else if (t == "area") {
            ObjectReader r(
                ctx, l, p,
                {"type", "corner", "edge_u", "edge_v", "color", "intensity", "samples", "casts_shadows"});
            scene.area_lights.push_back(parse_area_light(r));
        } else {
            ctx.fail(join(p, "type"), "unknown light type \"" + t + "\" (expected \"point\" or \"area\")");
        }
    }
}

Material parse_material(const Context& ctx, const Json& j, const std::string& path) {
    ObjectReader r(ctx, j, path,
                   {"name", "ambient", "diffuse", "specular", "specular_exponent", "refractive_index",
                    "reflectivity", "transmissivity", "diffuse_reflectance", "point_colors",
                    "use_point_colors", "intensity_range", "texture"});
    Material m;
    r.string("name", m.name);
    r.color("ambient", m.ambient, 1.0);
    r.color("diffuse", m.diffuse, 1.0);
    r.color("specular", m.specular, 1.0);
    if (r.number("specular_exponent", m.specular_exponent))
        r.require_non_negative("specular_exponent", m.specular_exponent);
    if (r.number("refractive_index", m.refractive_index) && !(m.refractive_index >= 1))
        ctx.fail(r.path("refractive_index"),
                 "must be >= 1 (relative to vacuum), got " + format_number(m.refractive_index));
    if (r.number("reflectivity", m.reflectivity)) r.require_unit_interval("reflectivity", m.reflectivity);
    if (r.number("transmissivity", m.transmissivity))
        r.require_unit_interval("transmissivity", m.transmissivity);
    // thesis 5.1: the three fractions add up to one unless the material absorbs light; when the
    // diffuse fraction is not given it is what the other two leave.
    if (r.number("diffuse_reflectance", m.diffuse_reflectance)) {
        r.require_unit_interval("diffuse_reflectance", m.diffuse_reflectance);
    } else {
        m.diffuse_reflectance = std::max(0.0f, 1.0f - m.reflectivity - m.transmissivity);
    }
    const double sum = double(m.reflectivity) + double(m.transmissivity) + double(m.diffuse_reflectance);
    if (sum > 1.0 + k_fraction_sum_tolerance) {
        const char* key = r.find("diffuse_reflectance") ? "diffuse_reflectance"
                          : r.find("transmissivity")    ? "transmissivity"
                                                        : "reflectivity";
        char sum_text[32];
        std::snprintf(sum_text, sizeof sum_text, "%.7g", sum);
        ctx.fail(r.path(key), std::string("reflectivity + transmissivity + diffuse_reflectance = ") +
                                  sum_text +
                                  " exceeds 1 (a material cannot send out more light than arrives)");
    }
    // point_colors, or its older boolean form use_point_colors (true: "colors", false: "none").
    std::string point_colors;
    if (r.string("point_colors", point_colors) && !parse_point_colors(point_colors, m.point_colors))
        ctx.fail(r.path("point_colors"),
                 "unknown value \"" + point_colors + "\" (expected auto, colors, intensity or none)");
    bool use_point_colors = true;
    if (r.boolean("use_point_colors", use_point_colors)) {
        if (r.find("point_colors"))
            ctx.fail(r.path("use_point_colors"),
                     "give point_colors or its older form use_point_colors, not both");
        m.point_colors = use_point_colors ? PointColors::colors : PointColors::none;
    }
    if (const Json* j = r.find("intensity_range")) {
        const std::string p = r.path("intensity_range");
        if (!j->is_array() || j->size() != 2)
            ctx.fail(p, "expected [lo, hi] (an array of 2 numbers), got " +
                            (j->is_array() ? "an array of " + std::to_string(j->size()) : type_name(*j)));
        std::array<float, 2> range{};
        for (std::size_t i = 0; i < 2; ++i) {
            const Json& e = (*j)[i];
            if (!e.is_number()) ctx.fail(join(p, i), "expected a number, got " + type_name(e));
            const double v = e.get<double>();
            if (!std::isfinite(v) || std::fabs(v) > std::numeric_limits<float>::max())
                ctx.fail(join(p, i), "expected a finite number that fits a 32-bit float");
            range[i] = static_cast<float>(v);
        }
        if (!(range[0] < range[1]))
            ctx.fail(join(p, 1), "must be greater than lo (" + format_number(range[0]) + "), got " +
                                     format_number(range[1]));
        m.intensity_range = range;
    }
    std::filesystem::path texture;
    if (r.file("texture", texture)) m.texture = texture.string();
    return m;
}

Transform parse_transform(const Context& ctx, const Json& j, const std::string& path) {
    ObjectReader r(ctx, j, path, {"translate", "rotate_degrees", "scale"});
    Transform t;
    r.vec3("translate", t.translate);
    r.vec3("rotate_degrees", t.rotate_degrees);
    if (r.number("scale", t.scale)) r.require_positive("scale", t.scale);
    return t;
}

Model parse_model(const Context& ctx, const Json& j, const std::string& path,
                  const std::vector<Material>& materials) {
    ObjectReader r(ctx, j, path, {"name", "pool", "source", "transform", "material", "surface"});
    Model m;
    const bool has_pool = r.file("pool", m.pool);
    const bool has_source = r.file("source", m.source);
    if (!has_pool && !has_source)
        ctx.fail(path, "a model needs \"pool\" (a .pool file) or \"source\" (a scan or patch file)");
    if (!r.string("name", m.name)) m.name = (has_pool ? m.pool : m.source).stem().string();
    if (const Json* t = r.find("transform")) m.transform = parse_transform(ctx, *t, r.path("transform"));
    if (const Json* mat = r.find("material")) {
        if (mat->is_string()) {
            const std::string name = mat->get<std::string>();
            auto it = std::find_if(materials.begin(), materials.end(),
                                   [&](const Material& x) { return x.name == name; });
            if (it == materials.end()) {
                std::string names;
                for (const Material& x : materials)
                    if (!x.name.empty()) names += (names.empty() ? "" : ", ") + x.name;
                ctx.fail(r.path("material"), "no material named \"" + name + "\" (named materials: " +
                                                 (names.empty() ? std::string("none") : names) + ")");
            }
            m.material = static_cast<std::uint32_t>(it - materials.begin());
        } else if (mat->is_number_integer()) {
            const bool negative = !mat->is_number_unsigned() && mat->get<std::int64_t>() < 0;
            if (negative || mat->get<std::uint64_t>() >= materials.size())
                ctx.fail(r.path("material"), "material index " + mat->dump() +
                                                 " out of range (the scene has " +
                                                 std::to_string(materials.size()) + " material" +
                                                 (materials.size() == 1 ? "" : "s") + ")");
            m.material = static_cast<std::uint32_t>(mat->get<std::uint64_t>());
        } else {
            ctx.fail(r.path("material"),
                     "expected a material name (string) or index (integer), got " + type_name(*mat));
        }
    }
    std::string surface;
    if (r.string("surface", surface) && !parse_surface(surface, m.surface))
        ctx.fail(r.path("surface"),
                 "unknown surface \"" + surface + "\" (expected " + std::string(k_surface_name_list) + ")");
    return m;
}

Environment parse_environment(const Context& ctx, const Json& j, const std::string& path) {
    ObjectReader r(ctx, j, path, {"color", "image", "intensity"});
    Environment e;
    r.color("color", e.color, std::numeric_limits<double>::infinity());
    r.file("image", e.image);
    if (r.number("intensity", e.intensity)) r.require_non_negative("intensity", e.intensity);
    return e;
}

RenderSettings parse_render(const Context& ctx, const Json& j, const std::string& path) {
    ObjectReader r(ctx, j, path,
                   {"max_bounces", "shadows", "reflections", "refractions", "exposure", "gamma", "spp",
                    "path_tracing", "caustics", "light_map"});
    RenderSettings s;
    r.integer("max_bounces", s.max_bounces, 0, k_max_bounces);
    r.boolean("shadows", s.shadows);
    r.boolean("reflections", s.reflections);
    r.boolean("refractions", s.refractions);
    if (r.number("exposure", s.exposure)) r.require_positive("exposure", s.exposure);
    if (r.number("gamma", s.gamma)) r.require_positive("gamma", s.gamma);
    r.integer("spp", s.spp, 1, k_max_spp);
    r.boolean("path_tracing", s.path_tracing);
    r.boolean("caustics", s.caustics);
    r.boolean("light_map", s.light_map);
    return s;
}

/// Parses JSON text, rejecting duplicate keys (nlohmann keeps the last silently) with their path.
Json parse_text(const Context& ctx, const std::string& text) {
    struct Frame {
        bool is_array = false;
        std::set<std::string> keys;
        std::string key;
        std::size_t index = 0;
    };
    std::vector<Frame> stack;
    std::string duplicate_path;
    auto current_path = [&stack]() {
        std::string p;
        for (const Frame& f : stack) {
            p += '/';
            p += f.is_array ? std::to_string(f.index) : pointer_token(f.key);
        }
        return p;
    };
    auto element_done = [&stack]() {
        if (!stack.empty() && stack.back().is_array) ++stack.back().index;
    };
    Json::parser_callback_t callback = [&](int, Json::parse_event_t event, Json& parsed) {
        switch (event) {
            case Json::parse_event_t::object_start:
                stack.push_back(Frame{});
                break;
            case Json::parse_event_t::array_start:
                stack.push_back(Frame{true, {}, {}, 0});
                break;
            case Json::parse_event_t::object_end:
            case Json::parse_event_t::array_end:
                if (!stack.empty()) stack.pop_back();
                element_done();
                break;
            case Json::parse_event_t::key:
                if (!stack.empty()) {
                    Frame& f = stack.back();
                    f.key = parsed.get<std::string>();
                    if (!f.keys.insert(f.key).second && duplicate_path.empty())
                        duplicate_path = current_path();
                }
                break;
            case Json::parse_event_t::value:
                element_done();
                break;
        }
        return true;
    };
    Json j;
    try {
        j = Json::parse(text, callback);
    } catch (const Json::exception& e) {
        std::string what = e.what();
        const auto close = what.find("] ");
        if (what.rfind("[json.exception", 0) == 0 && close != std::string::npos)
            what = what.substr(close + 2);
        // A syntax error carries its line and column; other failures (a number too large for a
        // double) are named by the path the parser had reached.
        if (dynamic_cast<const Json::parse_error*>(&e))
            throw Error(one_line(ctx.label + ": invalid JSON: " + what));
        ctx.fail(current_path(), "invalid JSON: " + what);
    }
    if (!duplicate_path.empty())
        ctx.fail(duplicate_path, "duplicate key (each key may appear once per object)");
    return j;
}

// ---- Writing ------------------------------------------------------------------------------------

using OJson = nlohmann::ordered_json;  // keeps keys in the documented order

OJson vec_json(const Vec3& v) {
    return OJson::array({v[0], v[1], v[2]});
}
/// A float as the shortest decimal that reads back as the same float ("0.8", not 0.800000011920929).
OJson float_json(float f) {
    char buf[32];
    const auto res = std::to_chars(buf, buf + sizeof buf, f);
    return std::strtod(std::string(buf, res.ptr).c_str(), nullptr);
}
OJson color_json(const Color& c) {
    return OJson::array({float_json(c[0]), float_json(c[1]), float_json(c[2])});
}

/// Indented JSON with arrays of plain values on one line ("[0, 1, 0]"), for people to read.
void write_pretty(const OJson& j, int indent, std::string& out) {
    const std::string pad(static_cast<std::size_t>(indent) + 2, ' ');
    if (j.is_object() && !j.empty()) {
        out += "{\n";
        std::size_t i = 0;
        for (const auto& [key, value] : j.items()) {
            out += pad + OJson(key).dump() + ": ";
            write_pretty(value, indent + 2, out);
            out += ++i < j.size() ? ",\n" : "\n";
        }
        out += std::string(static_cast<std::size_t>(indent), ' ') + "}";
    } else if (j.is_array() && !j.empty()) {
        const bool flat = std::none_of(j.begin(), j.end(), [](const OJson& e) { return e.is_structured(); });
        out += flat ? "[" : "[\n";
        for (std::size_t i = 0; i < j.size(); ++i) {
            if (!flat) out += pad;
            write_pretty(j[i], indent + 2, out);
            if (i + 1 < j.size()) out += flat ? ", " : ",\n";
        }
        out += flat ? "]" : "\n" + std::string(static_cast<std::size_t>(indent), ' ') + "]";
    } else {
        out += j.dump();
    }
}

}  // namespace

Scene parse_scene(const std::string& json_text, const std::string& label,
                  const std::filesystem::path& base_dir) {
    const Context ctx{label, base_dir};
    const Json root = parse_text(ctx, json_text);
    ObjectReader r(ctx, root, "", {"camera", "lights", "materials", "models", "environment", "render"});
    Scene scene;
    if (const Json* j = r.find("camera")) scene.camera = parse_camera(ctx, *j, r.path("camera"));
    if (const Json* j = r.find("lights")) parse_lights(ctx, *j, r.path("lights"), scene);
    if (const Json* j = r.find("materials")) {
        if (!j->is_array())
            ctx.fail(r.path("materials"), "expected an array of materials, got " + type_name(*j));
        for (std::size_t i = 0; i < j->size(); ++i) {
            const std::string p = join(r.path("materials"), i);
            Material m = parse_material(ctx, (*j)[i], p);
            for (std::size_t k = 0; k < scene.materials.size(); ++k)
                if (!m.name.empty() && scene.materials[k].name == m.name)
                    ctx.fail(join(p, "name"), "duplicate material name \"" + m.name + "\" (also " +
                                                  join(r.path("materials"), k) + ")");
            scene.materials.push_back(std::move(m));
        }
    }
    if (scene.materials.empty()) {
        Material m;
        m.name = "default";
        scene.materials.push_back(m);
    }
    if (const Json* j = r.find("models")) {
        if (!j->is_array()) ctx.fail(r.path("models"), "expected an array of models, got " + type_name(*j));
        for (std::size_t i = 0; i < j->size(); ++i)
            scene.models.push_back(parse_model(ctx, (*j)[i], join(r.path("models"), i), scene.materials));
    }
    if (const Json* j = r.find("environment"))
        scene.environment = parse_environment(ctx, *j, r.path("environment"));
    if (const Json* j = r.find("render")) scene.render = parse_render(ctx, *j, r.path("render"));
    return scene;
}

Scene load_scene(const std::filesystem::path& file) {
    std::error_code ec;
    if (std::filesystem::is_directory(file, ec))
        throw Error(file.string() + ": is a folder, not a scene file");
    std::ifstream in(file, std::ios::binary);
    if (!in) throw Error(file.string() + ": cannot open the scene file");
    std::ostringstream text;
    text << in.rdbuf();
    if (in.bad()) throw Error(file.string() + ": read error");
    std::filesystem::path dir = std::filesystem::absolute(file, ec).parent_path();
    if (ec) dir = file.parent_path();
    Scene scene = parse_scene(text.str(), file.string(), dir);
    scene.file = file;
    return scene;
}

std::string to_json(const Scene& scene) {
    OJson root = OJson::object();
    const Camera& c = scene.camera;
    root["camera"] = {{"position", vec_json(c.position)},
                      {"look_at", vec_json(c.look_at)},
                      {"up", vec_json(c.up)},
                      {"fov_y_degrees", c.fov_y_degrees},
                      {"width", c.width},
                      {"height", c.height}};
    OJson lights = OJson::array();
    for (const PointLight& l : scene.point_lights)
        lights.push_back({{"type", "point"},
                          {"position", vec_json(l.position)},
                          {"color", color_json(l.color)},
                          {"intensity", float_json(l.intensity)},
                          {"casts_shadows", l.casts_shadows}});
    for (const AreaLight& l : scene.area_lights)
        lights.push_back({{"type", "area"},
                          {"corner", vec_json(l.corner)},
                          {"edge_u", vec_json(l.edge_u)},
                          {"edge_v", vec_json(l.edge_v)},
                          {"color", color_json(l.color)},
                          {"intensity", float_json(l.intensity)},
                          {"samples", l.samples},
                          {"casts_shadows", l.casts_shadows}});
    root["lights"] = lights;
    OJson materials = OJson::array();
    for (const Material& m : scene.materials) {
        OJson j = OJson::object();
        if (!m.name.empty()) j["name"] = m.name;
        j["ambient"] = color_json(m.ambient);
        j["diffuse"] = color_json(m.diffuse);
        j["specular"] = color_json(m.specular);
        j["specular_exponent"] = float_json(m.specular_exponent);
        j["refractive_index"] = float_json(m.refractive_index);
        j["reflectivity"] = float_json(m.reflectivity);
        j["transmissivity"] = float_json(m.transmissivity);
        j["diffuse_reflectance"] = float_json(m.diffuse_reflectance);
        j["point_colors"] = point_colors_name(m.point_colors);
        if (m.intensity_range)
            j["intensity_range"] =
                OJson::array({float_json((*m.intensity_range)[0]), float_json((*m.intensity_range)[1])});
        if (!m.texture.empty()) j["texture"] = m.texture;
        materials.push_back(std::move(j));
    }
    root["materials"] = materials;
    OJson models = OJson::array();
    for (const Model& m : scene.models) {
        OJson j = OJson::object();
        j["name"] = m.name;
        if (!m.pool.empty()) j["pool"] = m.pool.string();
        if (!m.source.empty()) j["source"] = m.source.string();
        // By name when that name picks exactly this material, else by index.
        const bool by_name =
            m.material < scene.materials.size() && !scene.materials[m.material].name.empty() &&
            std::count_if(scene.materials.begin(), scene.materials.end(),
                          [&](const Material& x) { return x.name == scene.materials[m.material].name; }) == 1;
        if (by_name)
            j["material"] = scene.materials[m.material].name;
        else
            j["material"] = m.material;
        j["surface"] = std::string(surface_name(m.surface));
        j["transform"] = {{"translate", vec_json(m.transform.translate)},
                          {"rotate_degrees", vec_json(m.transform.rotate_degrees)},
                          {"scale", m.transform.scale}};
        models.push_back(std::move(j));
    }
    root["models"] = models;
    const Environment& e = scene.environment;
    root["environment"] = {{"color", color_json(e.color)}, {"intensity", float_json(e.intensity)}};
    if (!e.image.empty()) root["environment"]["image"] = e.image.string();
    const RenderSettings& s = scene.render;
    root["render"] = {{"max_bounces", s.max_bounces},
                      {"shadows", s.shadows},
                      {"reflections", s.reflections},
                      {"refractions", s.refractions},
                      {"exposure", float_json(s.exposure)},
                      {"gamma", float_json(s.gamma)},
                      {"spp", s.spp},
                      {"path_tracing", s.path_tracing},
                      {"caustics", s.caustics},
                      {"light_map", s.light_map}};
    std::string out;
    write_pretty(root, 0, out);
    return out + "\n";
}

const char* point_colors_name(PointColors p) {
    switch (p) {
        case PointColors::colors:
            return "colors";
        case PointColors::intensity:
            return "intensity";
        case PointColors::none:
            return "none";
        case PointColors::automatic:
            break;
    }
    return "auto";
}

bool parse_point_colors(const std::string& text, PointColors& out) {
    for (const PointColors p :
         {PointColors::automatic, PointColors::colors, PointColors::intensity, PointColors::none}) {
        if (text == point_colors_name(p)) {
            out = p;
            return true;
        }
    }
    return false;
}

std::array<float, 2> intensity_range(std::span<const float> intensities) {
    std::vector<float> v;
    v.reserve(intensities.size());
    for (const float x : intensities)
        if (std::isfinite(x)) v.push_back(x);
    if (v.empty()) return {0.0f, 0.0f};
    // Nearest rank: the value at index round(q (n - 1)) of the sorted values.
    auto at = [&](double q) {
        const auto k = static_cast<std::size_t>(std::llround(q * static_cast<double>(v.size() - 1)));
        std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
        return v[k];
    };
    const float lo = at(0.01);
    const float hi = at(0.99);
    return {lo, hi};
}

std::uint8_t intensity_grey(float intensity, float lo, float hi) {
    if (!std::isfinite(intensity)) return 0;
    if (!(hi > lo)) return 255;
    const double t =
        std::clamp((static_cast<double>(intensity) - lo) / (static_cast<double>(hi) - lo), 0.0, 1.0);
    // Linear t to sRGB (IEC 61966-2-1), the encoding point colors are stored in.
    const double e = t <= 0.0031308 ? 12.92 * t : 1.055 * std::pow(t, 1.0 / 2.4) - 0.055;
    return static_cast<std::uint8_t>(std::lround(std::clamp(e, 0.0, 1.0) * 255.0));
}

}  // namespace prt::scene
