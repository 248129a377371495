#include "ply_reader.h"

#include <algorithm>
#include <bit>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <limits>

#include "progress.h"
#include "prt/error.h"
#include "prt/mapped_file.h"
#include "quote.h"

namespace prt::pre::import {

namespace {

bool parse_type(std::string_view s, PlyType& t) {
    struct Name {
        const char* name;
        PlyType type;
    };
    static constexpr Name k_names[] = {
        {"char", PlyType::int8},      {"int8", PlyType::int8},       {"uchar", PlyType::uint8},
        {"uint8", PlyType::uint8},    {"short", PlyType::int16},     {"int16", PlyType::int16},
        {"ushort", PlyType::uint16},  {"uint16", PlyType::uint16},   {"int", PlyType::int32},
        {"int32", PlyType::int32},    {"uint", PlyType::uint32},     {"uint32", PlyType::uint32},
        {"float", PlyType::float32},  {"float32", PlyType::float32}, {"double", PlyType::float64},
        {"float64", PlyType::float64}};
    for (const Name& n : k_names)
        if (s == n.name) {
            t = n.type;
            return true;
        }
    return false;
}

bool is_integral(PlyType t) {
    return t != PlyType::float32 && t != PlyType::float64;
}

std::string line_ref(const std::string& label, std::size_t line) {
    return label + ": line " + std::to_string(line) + ": ";
}

// ---- binary values --------------------------------------------------------------------------

template <bool Swap, class U>
inline U load_raw(const unsigned char* p) {
    U v;
    std::memcpy(&v, p, sizeof v);
    if constexpr (Swap) {
        if constexpr (sizeof(U) == 2) v = static_cast<U>(__builtin_bswap16(v));
        if constexpr (sizeof(U) == 4) v = static_cast<U>(__builtin_bswap32(v));
        if constexpr (sizeof(U) == 8) v = static_cast<U>(__builtin_bswap64(v));
    }
    return v;
}

/// One scalar converted to double: a switch on a byte, not a virtual call, in the hot loop.
template <bool Swap>
inline double load_value(const unsigned char* p, PlyType t) {
    switch (t) {
        case PlyType::int8:
            return static_cast<std::int8_t>(*p);
        case PlyType::uint8:
            return *p;
        case PlyType::int16:
            return static_cast<std::int16_t>(load_raw<Swap, std::uint16_t>(p));
        case PlyType::uint16:
            return load_raw<Swap, std::uint16_t>(p);
        case PlyType::int32:
            return static_cast<std::int32_t>(load_raw<Swap, std::uint32_t>(p));
        case PlyType::uint32:
            return load_raw<Swap, std::uint32_t>(p);
        case PlyType::float32: {
            const std::uint32_t bits = load_raw<Swap, std::uint32_t>(p);
            float f;
            std::memcpy(&f, &bits, 4);
            return f;
        }
        case PlyType::float64: {
            const std::uint64_t bits = load_raw<Swap, std::uint64_t>(p);
            double d;
            std::memcpy(&d, &bits, 8);
            return d;
        }
    }
    return 0.0;
}

// ---- what we take from the vertex element ----------------------------------------------------

enum Slot : int {
    s_x,
    s_y,
    s_z,
    s_nx,
    s_ny,
    s_nz,
    s_red,
    s_green,
    s_blue,
    s_alpha,
    s_radius,
    s_intensity,
    s_count
};

struct VertexLayout {
    int property[s_count];  // property index per slot, -1 when absent
    PlyType type[s_count];
    std::size_t offset[s_count];  // byte offset in a fixed-stride binary row
    std::vector<int> slot_of;     // per property index: slot, or -1 (skipped)
    bool normals = false, colors = false, alpha = false, radius = false, intensity = false;
};

bool equal_nocase(std::string_view a, std::string_view b) {
    return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
               return std::tolower(static_cast<unsigned char>(x)) ==
                      std::tolower(static_cast<unsigned char>(y));
           });
}

/// Scanner return intensity: "intensity" (PCL, PDAL, the Stanford meshes), "scalar_Intensity"
/// (CloudCompare's scalar fields), "reflectance" (mobile mapping exports); any case.
bool is_intensity_name(std::string_view name) {
    return equal_nocase(name, "intensity") || equal_nocase(name, "scalar_intensity") ||
           equal_nocase(name, "reflectance");
}

bool is_color_name(std::string_view name) {
    for (const char* c : {"red", "green", "blue", "alpha", "diffuse_red", "diffuse_green", "diffuse_blue"})
        if (name == c) return true;
    return false;
}

VertexLayout make_layout(const PlyElement& vertex, const std::string& label, Report& report) {
    VertexLayout layout;
    std::fill(std::begin(layout.property), std::end(layout.property), -1);
    layout.slot_of.assign(vertex.properties.size(), -1);
    struct Alias {
        const char* name;
        Slot slot;
    };
    static constexpr Alias k_aliases[] = {{"x", s_x},
                                          {"y", s_y},
                                          {"z", s_z},
                                          {"nx", s_nx},
                                          {"ny", s_ny},
                                          {"nz", s_nz},
                                          {"normal_x", s_nx},
                                          {"normal_y", s_ny},
                                          {"normal_z", s_nz},
                                          {"red", s_red},
                                          {"green", s_green},
                                          {"blue", s_blue},
                                          {"alpha", s_alpha},
                                          {"diffuse_red", s_red},
                                          {"diffuse_green", s_green},
                                          {"diffuse_blue", s_blue},
                                          {"radius", s_radius}};
    std::size_t offset = 0;
    for (std::size_t i = 0; i < vertex.properties.size(); ++i) {
        const PlyProperty& p = vertex.properties[i];
        if (p.is_list && is_color_name(p.name))
            throw Error(label + ": vertex property " + quoted(std::string_view(p.name)) +
                        " is a list; a colour channel must be one number per vertex (uchar 0..255, or "
                        "float 0..1)");
        if (!p.is_list && layout.property[s_intensity] < 0 && is_intensity_name(p.name)) {
            layout.property[s_intensity] = static_cast<int>(i);
            layout.type[s_intensity] = p.type;
            layout.offset[s_intensity] = offset;
            layout.slot_of[i] = s_intensity;
        }
        for (const Alias& a : k_aliases) {
            if (p.name != a.name || p.is_list || layout.property[a.slot] >= 0) continue;
            layout.property[a.slot] = static_cast<int>(i);
            layout.type[a.slot] = p.type;
            layout.offset[a.slot] = offset;
            layout.slot_of[i] = a.slot;
            break;
        }
        offset += p.is_list ? 0 : ply_type_size(p.type);
    }
    for (int s : {s_x, s_y, s_z})
        if (layout.property[s] < 0)
            throw Error(label + ": the vertex element has no " +
                        (s == s_x   ? "x"
                         : s == s_y ? "y"
                                    : "z") +
                        " property (a scalar x, y and z are required)");
    auto all = [&](std::initializer_list<int> slots) {
        return std::all_of(slots.begin(), slots.end(), [&](int s) { return layout.property[s] >= 0; });
    };
    auto any = [&](std::initializer_list<int> slots) {
        return std::any_of(slots.begin(), slots.end(), [&](int s) { return layout.property[s] >= 0; });
    };
    layout.normals = all({s_nx, s_ny, s_nz});
    if (!layout.normals && any({s_nx, s_ny, s_nz})) {
        report.notes.push_back(label + ": vertex normals incomplete (needs nx, ny and nz): ignored");
        for (int s : {s_nx, s_ny, s_nz})
            if (layout.property[s] >= 0) layout.slot_of[layout.property[s]] = -1;
    }
    layout.colors = all({s_red, s_green, s_blue});
    if (!layout.colors && any({s_red, s_green, s_blue, s_alpha})) {
        report.notes.push_back(label + ": vertex colors incomplete (needs red, green and blue): ignored");
        for (int s : {s_red, s_green, s_blue, s_alpha})
            if (layout.property[s] >= 0) layout.slot_of[layout.property[s]] = -1;
    }
    layout.alpha = layout.colors && layout.property[s_alpha] >= 0;
    layout.radius = layout.property[s_radius] >= 0;
    layout.intensity = layout.property[s_intensity] >= 0;

    std::string skipped;
    for (std::size_t i = 0; i < vertex.properties.size(); ++i)
        if (layout.slot_of[i] < 0) skipped += (skipped.empty() ? "" : ", ") + vertex.properties[i].name;
    if (!skipped.empty()) report.notes.push_back(label + ": skipped vertex properties: " + skipped);
    return layout;
}

/// Color channel from a PLY value: floats 0..1, 16-bit integers 0..65535 (scaled), other integers
/// 0..255. A value outside its range (or NaN) is not a colour: returns -1.
inline int to_channel(double v, PlyType t) {
    double c = v;
    if (t == PlyType::float32 || t == PlyType::float64) {
        if (!(v >= 0.0 && v <= 1.0)) return -1;
        c = v * 255.0;
    } else if (t == PlyType::int16 || t == PlyType::uint16) {
        if (!(v >= 0.0)) return -1;
        c = v / 257.0;
    } else if (!(v >= 0.0 && v <= 255.0)) {
        return -1;
    }
    return static_cast<int>(std::lround(c));
}

/// The output arrays, sized as rows arrive.
struct Sink {
    PointCloud& cloud;
    const VertexLayout& layout;
    const PlyElement& vertex;
    const std::string& label;
    /// Chunked reading (read_ply_chunks): rows go to `cloud` `chunk` at a time, each full chunk
    /// handed to `flush`; 0 keeps every row.
    std::size_t chunk = 0;
    const std::function<void(const PointCloud&)>* flush = nullptr;
    std::uint64_t base = 0;    ///< global index of cloud's first row (chunked)
    std::uint64_t stored = 0;  ///< rows stored so far (chunked)
    void resize(std::size_t n) {
        if (chunk) n = std::min(n, chunk);
        cloud.positions.resize(n);
        if (layout.normals) cloud.normals.resize(n);
        if (layout.colors) cloud.colors.resize(n);
        if (layout.radius) cloud.radii.resize(n);
        if (layout.intensity) cloud.intensities.resize(n);
    }
    [[noreturn]] void bad_color(std::size_t i, int slot, double value) const {
        const PlyType t = layout.type[slot];
        const char* range = t == PlyType::float32 || t == PlyType::float64 ? "0..1 (a float colour)"
                            : t == PlyType::int16 || t == PlyType::uint16  ? "0..65535 (a 16-bit colour)"
                                                                           : "0..255";
        char buf[64];
        std::snprintf(buf, sizeof buf, "%.9g", value);
        throw Error(label + ": vertex " + std::to_string(i) + ": " +
                    vertex.properties[static_cast<std::size_t>(layout.property[slot])].name + " = " + buf +
                    " is outside " + range);
    }
    inline std::uint8_t channel(std::size_t i, int slot, double value) const {
        const int c = to_channel(value, layout.type[slot]);
        if (c < 0) bad_color(i, slot, value);
        return static_cast<std::uint8_t>(c);
    }
    /// Hands the rows not yet flushed to `flush` (chunked reading, at the end of the element).
    void finish_chunks() {
        if (!chunk || stored == base) return;
        resize(static_cast<std::size_t>(stored - base));
        (*flush)(cloud);
        base = stored;
    }
    /// Stores one row from per-slot values.
    inline void store(std::size_t row, const double* v) {
        std::size_t i = row;
        if (chunk) {
            if (row - base == chunk) {
                (*flush)(cloud);
                base += chunk;
            }
            i = static_cast<std::size_t>(row - base);
            stored = row + 1;
        }
        cloud.positions[i] = {v[s_x], v[s_y], v[s_z]};
        if (layout.normals)
            cloud.normals[i] = {static_cast<float>(v[s_nx]), static_cast<float>(v[s_ny]),
                                static_cast<float>(v[s_nz])};
        if (layout.colors)
            cloud.colors[i] = {channel(row, s_red, v[s_red]), channel(row, s_green, v[s_green]),
                               channel(row, s_blue, v[s_blue]),
                               layout.alpha ? channel(row, s_alpha, v[s_alpha]) : std::uint8_t{255}};
        if (layout.radius) cloud.radii[i] = static_cast<float>(v[s_radius]);
        if (layout.intensity) cloud.intensities[i] = static_cast<float>(v[s_intensity]);
    }
};

/// The scanner position of a PLY "camera" element (the VCG / MeshLab and PCL PLYWriter
/// convention: view_px view_py view_pz, the viewpoint in the vertices' frame).
struct CameraLayout {
    std::vector<int> slot_of;  // per property: 0, 1, 2 for view_px/py/pz, -1 otherwise
    bool complete = false;
};

CameraLayout camera_layout(const PlyElement& camera) {
    CameraLayout c;
    c.slot_of.assign(camera.properties.size(), -1);
    int found = 0;
    for (std::size_t i = 0; i < camera.properties.size(); ++i) {
        const PlyProperty& p = camera.properties[i];
        if (p.is_list) continue;
        const int slot = p.name == "view_px" ? 0 : p.name == "view_py" ? 1 : p.name == "view_pz" ? 2 : -1;
        if (slot >= 0 && !(found & (1 << slot))) {
            c.slot_of[i] = slot;
            found |= 1 << slot;
        }
    }
    c.complete = found == 7;
    return c;
}

constexpr std::uint64_t k_progress_every = 1u << 16;

/// The data of `el` ends after `have` of its rows (binary and ASCII bodies alike).
[[noreturn]] void throw_truncated(const std::string& label, const PlyElement& el, std::uint64_t have) {
    if (el.name == "vertex")
        throw Error(label + ": header declares " + std::to_string(el.count) +
                    " vertices but the data ends after " + std::to_string(have));
    throw Error(label + ": header declares " + std::to_string(el.count) + " '" + el.name +
                "' rows but the data ends after " + std::to_string(have));
}

// ---- binary -------------------------------------------------------------------------------------

template <bool Swap>
class BinaryReader {
public:
    BinaryReader(const unsigned char* begin, const unsigned char* end, const std::string& label)
        : m_p(begin), m_end(end), m_label(label) {}

    std::size_t remaining() const { return static_cast<std::size_t>(m_end - m_p); }

    /// Walks one variable-size row; stores scalar values of wanted properties. False when the
    /// data ends inside the row.
    bool walk_row(const PlyElement& el, const std::vector<int>* slot_of, double* values) {
        const unsigned char* p = m_p;
        for (std::size_t k = 0; k < el.properties.size(); ++k) {
            const PlyProperty& prop = el.properties[k];
            if (prop.is_list) {
                const std::size_t cs = ply_type_size(prop.count_type);
                if (static_cast<std::size_t>(m_end - p) < cs) return false;
                const double count = load_value<Swap>(p, prop.count_type);
                p += cs;
                if (count < 0)
                    throw Error(m_label + ": element '" + el.name + "': negative list length in property '" +
                                prop.name + "'");
                const std::size_t bytes = static_cast<std::size_t>(count) * ply_type_size(prop.type);
                if (static_cast<std::size_t>(m_end - p) < bytes) return false;
                p += bytes;
            } else {
                const std::size_t s = ply_type_size(prop.type);
                if (static_cast<std::size_t>(m_end - p) < s) return false;
                if (slot_of && (*slot_of)[k] >= 0) values[(*slot_of)[k]] = load_value<Swap>(p, prop.type);
                p += s;
            }
        }
        m_p = p;
        return true;
    }

    void skip_element(const PlyElement& el) {
        if (el.properties.empty()) return;  // rows of zero bytes
        const std::size_t stride = el.fixed_stride();
        if (stride > 0) {
            const std::uint64_t have = remaining() / stride;
            if (have < el.count) truncated(el, have);
            m_p += el.count * stride;
            return;
        }
        for (std::uint64_t i = 0; i < el.count; ++i)
            if (!walk_row(el, nullptr, nullptr)) truncated(el, i);
    }

    /// Reads the first row's wanted values, skips the rest of the element.
    void read_first_row(const PlyElement& el, const std::vector<int>& slot_of, double* values) {
        if (el.count == 0) return;
        if (!walk_row(el, &slot_of, values)) truncated(el, 0);
        PlyElement rest = el;
        rest.count = el.count - 1;
        skip_element(rest);
    }

    void read_vertices(const PlyElement& el, const VertexLayout& layout, Sink& sink, LazyProgress& progress) {
        const std::size_t stride = el.fixed_stride();
        double v[s_count] = {};
        if (stride > 0) {
            // Fixed-size rows: check the whole element fits before allocating anything.
            const std::uint64_t have = remaining() / stride;
            if (have < el.count) truncated(el, have);
            sink.resize(el.count);
            const unsigned char* row = m_p;
            int slots[s_count];
            int n_slots = 0;
            for (int s = 0; s < s_count; ++s)
                if (layout.property[s] >= 0 && layout.slot_of[layout.property[s]] == s) slots[n_slots++] = s;
            for (std::uint64_t i = 0; i < el.count; ++i, row += stride) {
                for (int k = 0; k < n_slots; ++k) {
                    const int s = slots[k];
                    v[s] = load_value<Swap>(row + layout.offset[s], layout.type[s]);
                }
                sink.store(i, v);
                if ((i & (k_progress_every - 1)) == 0) progress.update(i);
            }
            m_p += el.count * stride;
            return;
        }
        // Rows with list properties: walk each row.
        std::size_t min_row = 0;
        for (const PlyProperty& p : el.properties)
            min_row += p.is_list ? ply_type_size(p.count_type) : ply_type_size(p.type);
        if (remaining() / std::max<std::size_t>(min_row, 1) < el.count)
            truncated(el, remaining() / std::max<std::size_t>(min_row, 1));
        sink.resize(el.count);
        for (std::uint64_t i = 0; i < el.count; ++i) {
            if (!walk_row(el, &layout.slot_of, v)) truncated(el, i);
            sink.store(i, v);
            if ((i & (k_progress_every - 1)) == 0) progress.update(i);
        }
    }

    [[noreturn]] void truncated(const PlyElement& el, std::uint64_t have) const {
        throw_truncated(m_label, el, have);
    }

private:
    const unsigned char* m_p;
    const unsigned char* m_end;
    const std::string& m_label;
};

// ---- ASCII --------------------------------------------------------------------------------------

class AsciiReader {
public:
    AsciiReader(const char* begin, const char* end, std::size_t first_line, const std::string& label)
        : m_p(begin), m_end(end), m_line(first_line), m_label(label) {}

    std::size_t line() const { return m_line; }

    bool next(std::string_view& token) {
        while (m_p < m_end) {
            const char c = *m_p;
            if (c == '\n')
                ++m_line;
            else if (c != ' ' && c != '\t' && c != '\r' && c != '\f' && c != '\v')
                break;
            ++m_p;
        }
        if (m_p == m_end) return false;
        const char* start = m_p;
        while (m_p < m_end && *m_p != ' ' && *m_p != '\n' && *m_p != '\t' && *m_p != '\r') ++m_p;
        token = {start, static_cast<std::size_t>(m_p - start)};
        return true;
    }

    double number(std::string_view tok, const PlyElement& el, std::uint64_t row,
                  const PlyProperty& prop) const {
        const char* b = tok.data();
        const char* e = b + tok.size();
        if (b < e && *b == '+') ++b;
        double v = 0;
        const auto [ptr, ec] = std::from_chars(b, e, v);
        if (ec == std::errc::result_out_of_range) return std::numeric_limits<double>::infinity();
        if (ec != std::errc() || ptr != e)
            throw Error(line_ref(m_label, m_line) + quoted(tok) + " is not a number (" + el.name + " " +
                        std::to_string(row) + ", property " + prop.name + ")");
        return v;
    }

    /// Reads one row; false when the data ends inside it.
    bool row(const PlyElement& el, std::uint64_t index, const std::vector<int>* slot_of, double* values) {
        std::string_view tok;
        for (std::size_t k = 0; k < el.properties.size(); ++k) {
            const PlyProperty& prop = el.properties[k];
            if (!next(tok)) return false;
            if (prop.is_list) {
                std::uint64_t count = 0;
                const auto [ptr, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), count);
                if (ec != std::errc() || ptr != tok.data() + tok.size())
                    throw Error(line_ref(m_label, m_line) + quoted(tok) + " is not a list length (" +
                                el.name + " " + std::to_string(index) + ", property " + prop.name + ")");
                for (std::uint64_t j = 0; j < count; ++j)
                    if (!next(tok)) return false;
            } else if (slot_of && (*slot_of)[k] >= 0) {
                values[(*slot_of)[k]] = number(tok, el, index, prop);
            }
        }
        return true;
    }

    void skip_element(const PlyElement& el) {
        if (el.properties.empty()) return;  // rows of zero tokens
        for (std::uint64_t i = 0; i < el.count; ++i)
            if (!row(el, i, nullptr, nullptr)) truncated(el, i);
    }

    /// Reads the first row's wanted values, skips the rest of the element.
    void read_first_row(const PlyElement& el, const std::vector<int>& slot_of, double* values) {
        if (el.count == 0) return;
        if (!row(el, 0, &slot_of, values)) truncated(el, 0);
        PlyElement rest = el;
        rest.count = el.count - 1;
        skip_element(rest);
    }

    void read_vertices(const PlyElement& el, const VertexLayout& layout, Sink& sink, LazyProgress& progress) {
        // Grow as rows arrive (doubling): a header declaring far more rows than the text holds
        // fails at the end of the data without having allocated for its count.
        std::size_t capacity = static_cast<std::size_t>(std::min<std::uint64_t>(el.count, 1u << 16));
        sink.resize(capacity);
        double v[s_count] = {};
        for (std::uint64_t i = 0; i < el.count; ++i) {
            if (!row(el, i, &layout.slot_of, v)) truncated(el, i);
            if (i >= capacity) {
                capacity = static_cast<std::size_t>(
                    std::min<std::uint64_t>(el.count, 2 * static_cast<std::uint64_t>(capacity)));
                sink.resize(capacity);
            }
            sink.store(i, v);
            if ((i & (k_progress_every - 1)) == 0) progress.update(i);
        }
    }

    /// Whether only whitespace follows.
    bool at_end() {
        std::string_view tok;
        const std::size_t line = m_line;
        const bool more = next(tok);
        m_trailing_line = m_line;
        m_line = line;
        return !more;
    }
    std::size_t trailing_line() const { return m_trailing_line; }

    [[noreturn]] void truncated(const PlyElement& el, std::uint64_t have) const {
        throw_truncated(m_label, el, have);
    }

private:
    const char* m_p;
    const char* m_end;
    std::size_t m_line;
    std::size_t m_trailing_line = 0;
    const std::string& m_label;
};

/// Reads a body element by element (binary or ASCII `reader`): the first "vertex" element into
/// `sink`, the first row of `camera` into `view`, every other element skipped.
template <class Reader>
void read_elements(Reader& reader, const PlyHeader& header, const VertexLayout& layout, Sink& sink,
                   const PlyElement* camera, const CameraLayout& camera_slots, double* view,
                   LazyProgress& progress) {
    bool seen_vertex = false;
    for (const PlyElement& el : header.elements) {
        if (el.name == "vertex" && !seen_vertex) {
            seen_vertex = true;
            reader.read_vertices(el, layout, sink, progress);
        } else if (&el == camera) {
            reader.read_first_row(el, camera_slots.slot_of, view);
        } else {
            reader.skip_element(el);
        }
    }
}

template <bool Swap>
void read_binary(const MappedFile& file, const PlyHeader& header, const VertexLayout& layout, Sink& sink,
                 const PlyElement* camera, const CameraLayout& camera_slots, double* view, Report& report,
                 LazyProgress& progress) {
    const auto* base = reinterpret_cast<const unsigned char*>(file.data());
    BinaryReader<Swap> reader(base + header.data_offset, base + file.size(), file.label());
    read_elements(reader, header, layout, sink, camera, camera_slots, view, progress);
    if (reader.remaining() > 0)
        report.notes.push_back(file.label() + ": warning: " + std::to_string(reader.remaining()) +
                               " bytes after the last declared element (the header may declare fewer "
                               "rows than the file holds; they were not read)");
}

}  // namespace

// ---- header -------------------------------------------------------------------------------------

std::size_t PlyElement::fixed_stride() const {
    std::size_t stride = 0;
    for (const PlyProperty& p : properties) {
        if (p.is_list) return 0;
        stride += ply_type_size(p.type);
    }
    return stride;
}

const PlyProperty* PlyElement::find(std::string_view property) const {
    for (const PlyProperty& p : properties)
        if (p.name == property) return &p;
    return nullptr;
}

const PlyElement* PlyHeader::find(std::string_view element) const {
    for (const PlyElement& e : elements)
        if (e.name == element) return &e;
    return nullptr;
}

std::uint64_t PlyHeader::face_count() const {
    const PlyElement* f = find("face");
    return f ? f->count : 0;
}

bool PlyHeader::has_vertex_normals() const {
    const PlyElement* v = find("vertex");
    if (!v) return false;
    auto scalar = [&](const char* a, const char* b) {
        const PlyProperty* p = v->find(a);
        if (!p) p = v->find(b);
        return p && !p->is_list;
    };
    return scalar("nx", "normal_x") && scalar("ny", "normal_y") && scalar("nz", "normal_z");
}

const char* ply_encoding_name(PlyEncoding e) {
    switch (e) {
        case PlyEncoding::ascii:
            return "ascii";
        case PlyEncoding::binary_little_endian:
            return "binary_little_endian";
        case PlyEncoding::binary_big_endian:
            return "binary_big_endian";
    }
    return "?";
}

PlyHeader parse_ply_header(std::string_view bytes, const std::string& label) {
    if (bytes.empty()) throw Error(label + ": file is empty");
    if (bytes.size() < 4 || bytes.substr(0, 3) != "ply" || (bytes[3] != '\n' && bytes[3] != '\r'))
        throw Error(label + ": not a PLY file (it does not start with a 'ply' line)");
    // A header longer than this is garbage, not a header: stop before scanning a huge file.
    constexpr std::size_t k_max_header_bytes = 1u << 20;
    PlyHeader header;
    bool have_format = false;
    std::size_t pos = 0;
    std::size_t line_no = 0;
    while (true) {
        if (pos >= bytes.size()) throw Error(label + ": PLY header has no end_header line");
        if (pos > k_max_header_bytes)
            throw Error(label + ": PLY header runs past 1 MiB without an end_header line");
        const std::size_t eol = bytes.find('\n', pos);
        const std::string_view line =
            bytes.substr(pos, eol == std::string_view::npos ? bytes.size() - pos : eol - pos);
        const std::size_t next = eol == std::string_view::npos ? bytes.size() : eol + 1;
        ++line_no;
        pos = next;
        if (line_no == 1) continue;  // "ply"
        const auto words = split_words(line);
        if (words.empty()) continue;
        const std::string_view kw = words[0];
        if (kw == "comment" || kw == "obj_info") continue;
        if (kw == "format") {
            if (words.size() != 3) throw Error(line_ref(label, line_no) + "expected 'format ENCODING 1.0'");
            if (words[1] == "ascii")
                header.encoding = PlyEncoding::ascii;
            else if (words[1] == "binary_little_endian")
                header.encoding = PlyEncoding::binary_little_endian;
            else if (words[1] == "binary_big_endian")
                header.encoding = PlyEncoding::binary_big_endian;
            else
                throw Error(line_ref(label, line_no) + "unknown PLY format " + quoted(words[1]) +
                            " (ascii, binary_little_endian or binary_big_endian)");
            if (words[2].substr(0, 2) != "1.")
                throw Error(line_ref(label, line_no) + "unsupported PLY version " + quoted(words[2]));
            have_format = true;
        } else if (kw == "element") {
            if (words.size() != 3) throw Error(line_ref(label, line_no) + "expected 'element NAME COUNT'");
            PlyElement el;
            el.name = std::string(words[1]);
            const auto [ptr, ec] =
                std::from_chars(words[2].data(), words[2].data() + words[2].size(), el.count);
            if (ec != std::errc() || ptr != words[2].data() + words[2].size())
                throw Error(line_ref(label, line_no) + "element '" + el.name + "' has an invalid count " +
                            quoted(words[2]));
            header.elements.push_back(std::move(el));
        } else if (kw == "property") {
            if (header.elements.empty())
                throw Error(line_ref(label, line_no) + "property before any element");
            PlyProperty prop;
            if (words.size() >= 2 && words[1] == "list") {
                if (words.size() != 5)
                    throw Error(line_ref(label, line_no) +
                                "expected 'property list COUNT_TYPE ITEM_TYPE NAME'");
                if (!parse_type(words[2], prop.count_type) || !is_integral(prop.count_type))
                    throw Error(line_ref(label, line_no) + "invalid list count type " + quoted(words[2]));
                if (!parse_type(words[3], prop.type))
                    throw Error(line_ref(label, line_no) + "unknown property type " + quoted(words[3]));
                prop.is_list = true;
                prop.name = std::string(words[4]);
            } else {
                if (words.size() != 3)
                    throw Error(line_ref(label, line_no) + "expected 'property TYPE NAME'");
                if (!parse_type(words[1], prop.type))
                    throw Error(line_ref(label, line_no) + "unknown property type " + quoted(words[1]));
                prop.name = std::string(words[2]);
            }
            header.elements.back().properties.push_back(std::move(prop));
        } else if (kw == "end_header") {
            header.data_offset = next;
            header.header_lines = line_no;
            break;
        } else {
            throw Error(line_ref(label, line_no) + "unknown PLY header keyword " + quoted(kw));
        }
    }
    if (!have_format) throw Error(label + ": PLY header has no format line");
    return header;
}

// ---- reader -------------------------------------------------------------------------------------

namespace {

PointCloud read_ply_impl(const std::filesystem::path& path, Report& report, bool quiet, std::size_t chunk,
                         const std::function<void(const PointCloud&)>* flush) {
    const MappedFile file = MappedFile::open(path);
    const std::string& label = file.label();
    const PlyHeader header = parse_ply_header(file.view(), label);
    const PlyElement* vertex = header.find("vertex");
    if (!vertex) throw Error(label + ": PLY file has no vertex element");
    const VertexLayout layout = make_layout(*vertex, label, report);

    // The scanner: one "camera" element row with view_px, view_py, view_pz.
    const PlyElement* camera = header.find("camera");
    CameraLayout camera_slots;
    if (camera) {
        camera_slots = camera_layout(*camera);
        if (!camera_slots.complete || camera->count != 1) {
            report.notes.push_back(label + ": camera element " +
                                   (camera_slots.complete
                                        ? "has " + std::to_string(camera->count) + " rows"
                                        : std::string("lacks view_px, view_py or view_pz")) +
                                   ": no sensor taken from it");
            camera = nullptr;
        }
    }
    double view[3] = {0, 0, 0};

    std::string skipped;
    for (const PlyElement& el : header.elements)
        if (&el != vertex && &el != camera)
            skipped += (skipped.empty() ? "" : ", ") + el.name + " (" + std::to_string(el.count) + " rows)";
    if (!skipped.empty()) report.notes.push_back(label + ": skipped elements: " + skipped);

    PointCloud cloud;
    Sink sink{cloud, layout, *vertex, label};
    // Chunked: after each chunk the pages of the mapped file read so far leave the resident set.
    const std::function<void(const PointCloud&)> flush_and_drop = [&](const PointCloud& c) {
        (*flush)(c);
        drop_mapped_pages(file.data(), file.size());
    };
    if (chunk) {
        sink.chunk = chunk;
        sink.flush = &flush_and_drop;
    }
    LazyProgress progress("reading " + label, vertex->count, quiet);
    switch (header.encoding) {
        case PlyEncoding::ascii: {
            AsciiReader reader(file.data() + header.data_offset, file.data() + file.size(),
                               header.header_lines + 1, label);
            read_elements(reader, header, layout, sink, camera, camera_slots, view, progress);
            if (!reader.at_end())
                report.notes.push_back(label +
                                       ": warning: data continues after the last declared element (line " +
                                       std::to_string(reader.trailing_line()) +
                                       "; the header may declare fewer rows than the file holds; not read)");
            break;
        }
        case PlyEncoding::binary_little_endian:
        case PlyEncoding::binary_big_endian:
            // Swap bytes when the file's byte order is not this machine's.
            if ((header.encoding == PlyEncoding::binary_big_endian) ==
                (std::endian::native == std::endian::little))
                read_binary<true>(file, header, layout, sink, camera, camera_slots, view, report, progress);
            else
                read_binary<false>(file, header, layout, sink, camera, camera_slots, view, report, progress);
            break;
    }
    sink.finish_chunks();
    progress.finish();
    if (camera) {
        for (int a = 0; a < 3; ++a)
            if (!std::isfinite(view[a]))
                throw Error(label + ": camera element: view_p" + "xyz"[a] + " is not finite");
        cloud.sensors.push_back(pool::Sensor{{view[0], view[1], view[2]}, pool::k_sensor_point, 0});
        report.sensor_source = "the PLY camera element (view_px view_py view_pz)";
    }
    report.reader = std::string("ply (") + ply_encoding_name(header.encoding) + ")";
    report.records = chunk ? sink.stored : cloud.size();
    if (chunk) {  // the rows went to `flush`; the sensor stays
        PointCloud rest;
        rest.sensors = std::move(cloud.sensors);
        rest.flags = cloud.flags;
        cloud = std::move(rest);
    }
    return cloud;
}

}  // namespace

PointCloud read_ply(const std::filesystem::path& path, Report& report, bool quiet) {
    return read_ply_impl(path, report, quiet, 0, nullptr);
}

PointCloud read_ply_chunks(const std::filesystem::path& path, Report& report, bool quiet, std::size_t chunk,
                           const std::function<void(const PointCloud&)>& flush) {
    return read_ply_impl(path, report, quiet, std::max<std::size_t>(chunk, 1), &flush);
}

}  // namespace prt::pre::import
