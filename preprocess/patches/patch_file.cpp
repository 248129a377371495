// prt-patches: .bpt and Newell patch file readers with one-line "FILE:LINE: problem" errors.
#include "patch_file.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <sstream>

#include "prt/error.h"

namespace prt::patches {

namespace {

/// Elements reserved before reading (more grow as lines arrive).
constexpr std::uint64_t k_reserve_max = 1u << 16;

/// Fewest bytes of text one element can take: a .bpt patch ("3 3" and 16 lines "0 0 0"), a
/// Newell index line (16 one-digit indices and 15 separators), a vertex line ("0 0 0").
constexpr std::uint64_t k_min_bpt_patch_bytes = 4 + 16 * 6;
constexpr std::uint64_t k_min_index_line_bytes = 32;
constexpr std::uint64_t k_min_vertex_bytes = 6;

/// How many of `count` claimed elements to reserve: never more than the text can hold (a short
/// file claiming pool::k_max_patches patches reserves almost nothing; issue 10, found by the
/// resource-limit tests), nor more than k_reserve_max elements.
std::uint64_t reserve_count(std::uint64_t count, std::string_view text, std::uint64_t min_bytes,
                            std::uint64_t cap = k_reserve_max) {
    return std::min({count, text.size() / min_bytes + 1, cap});
}

/// Longest token quoted back in an error message.
constexpr std::size_t k_quote_max = 40;

std::string quote(std::string_view s) {
    std::string q(s.substr(0, k_quote_max));
    for (char& c : q)
        if (!std::isprint(static_cast<unsigned char>(c))) c = '?';
    return "'" + q + (s.size() > k_quote_max ? "...'" : "'");
}

bool is_space(char c) {
    return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
}

/// The file's lines with their numbers; blank lines are skipped.
class LineReader {
public:
    LineReader(std::string_view text, const std::string& label) : m_text(text), m_label(label) {}

    /// Next non-blank line (trimmed); false at the end of the file.
    bool next(std::string_view& line) {
        while (m_pos < m_text.size()) {
            const std::size_t nl = m_text.find('\n', m_pos);
            const std::size_t end = nl == std::string_view::npos ? m_text.size() : nl;
            std::string_view l = m_text.substr(m_pos, end - m_pos);
            m_pos = nl == std::string_view::npos ? m_text.size() : nl + 1;
            ++m_line;
            if (std::memchr(l.data(), '\0', l.size()))
                fail("NUL byte in the line (a binary file, not a patch file)");
            std::size_t a = 0, b = l.size();
            while (a < b && is_space(l[a])) ++a;
            while (b > a && is_space(l[b - 1])) --b;
            if (a == b) continue;
            line = l.substr(a, b - a);
            return true;
        }
        return false;
    }

    std::size_t line_number() const { return m_line; }
    [[noreturn]] void fail(const std::string& what) const {
        throw Error(m_label + ":" + std::to_string(m_line) + ": " + what);
    }
    [[noreturn]] void fail_at(std::size_t line, const std::string& what) const {
        throw Error(m_label + ":" + std::to_string(line) + ": " + what);
    }
    [[noreturn]] void fail_eof(const std::string& what) const {
        throw Error(m_label + ":" + std::to_string(std::max<std::size_t>(m_line, 1)) +
                    ": unexpected end of file " + what);
    }

private:
    std::string_view m_text;
    const std::string& m_label;
    std::size_t m_pos = 0;
    std::size_t m_line = 0;
};

/// Splits a line into fields separated by commas and/or whitespace; an empty field between two
/// commas (or a leading / trailing comma) is an error.
std::vector<std::string_view> fields(std::string_view line, const LineReader& reader) {
    std::vector<std::string_view> out;
    const bool commas = line.find(',') != std::string_view::npos;
    std::size_t i = 0;
    while (i <= line.size()) {
        if (commas) {
            const std::size_t end = std::min(line.find(',', i), line.size());
            std::string_view piece = line.substr(i, end - i);
            std::size_t a = 0, b = piece.size();
            while (a < b && is_space(piece[a])) ++a;
            while (b > a && is_space(piece[b - 1])) --b;
            piece = piece.substr(a, b - a);
            if (piece.empty()) reader.fail("empty field between commas");
            // whitespace inside a comma field separates fields too ("1 2, 3" is three numbers)
            std::size_t j = 0;
            while (j < piece.size()) {
                std::size_t k = j;
                while (k < piece.size() && !is_space(piece[k])) ++k;
                out.push_back(piece.substr(j, k - j));
                while (k < piece.size() && is_space(piece[k])) ++k;
                j = k;
            }
            i = end + 1;
        } else {
            while (i < line.size() && is_space(line[i])) ++i;
            if (i >= line.size()) break;
            std::size_t k = i;
            while (k < line.size() && !is_space(line[k])) ++k;
            out.push_back(line.substr(i, k - i));
            i = k;
        }
    }
    return out;
}

bool parse_uint(std::string_view s, std::uint64_t& value) {
    if (!s.empty() && s[0] == '+') s.remove_prefix(1);
    if (s.empty()) return false;
    const auto r = std::from_chars(s.data(), s.data() + s.size(), value);
    return r.ec == std::errc() && r.ptr == s.data() + s.size();
}

std::uint64_t expect_uint(std::string_view s, const LineReader& reader, const std::string& what) {
    std::uint64_t v = 0;
    if (!parse_uint(s, v)) reader.fail(what + ": " + quote(s) + " is not a whole number");
    return v;
}

double expect_double(std::string_view s, const LineReader& reader, const std::string& what) {
    std::string_view t = s;
    if (!t.empty() && t[0] == '+') t.remove_prefix(1);
    double v = 0.0;
    const auto r = std::from_chars(t.data(), t.data() + t.size(), v);
    if (t.empty() || r.ec == std::errc::invalid_argument || r.ptr != t.data() + t.size())
        reader.fail(what + ": " + quote(s) + " is not a number");
    if (r.ec == std::errc::result_out_of_range || !std::isfinite(v))
        reader.fail(what + ": " + quote(s) + " is not a finite number");
    return v;
}

/// The count line: one whole number in [1, limit].
std::uint64_t read_count(LineReader& reader, const std::string& what, std::uint64_t limit,
                         const std::string& eof_context) {
    std::string_view line;
    if (!reader.next(line)) reader.fail_eof(eof_context + ": expected the " + what);
    const auto f = fields(line, reader);
    if (f.size() != 1)
        reader.fail("expected the " + what + " (one whole number), got " + std::to_string(f.size()) +
                    " fields");
    const std::uint64_t n = expect_uint(f[0], reader, "the " + what);
    if (n == 0) reader.fail("the " + what + " is 0");
    if (n > limit)
        reader.fail("the " + what + " " + std::to_string(n) + " exceeds the limit of " +
                    std::to_string(limit));
    return n;
}

pool::PatchPoint read_point(std::string_view line, const LineReader& reader, const std::string& what) {
    const auto f = fields(line, reader);
    if (f.size() != 3)
        reader.fail(what + ": expected 3 coordinates x y z, got " + std::to_string(f.size()) + " fields");
    return {expect_double(f[0], reader, what), expect_double(f[1], reader, what),
            expect_double(f[2], reader, what)};
}

void expect_end(LineReader& reader, const std::string& after) {
    std::string_view line;
    if (reader.next(line)) reader.fail("unexpected content after " + after + ": " + quote(line));
}

PatchSet parse_bpt(std::string_view text, const std::string& label) {
    LineReader reader(text, label);
    PatchSet set;
    set.format = PatchFormat::bpt;
    const std::uint64_t count = read_count(reader, "patch count", pool::k_max_patches, "(empty file)");
    // Storage grows with the lines actually read: a header claiming millions of patches in a short
    // file allocates nothing up front.
    set.nets.reserve(reserve_count(count, text, k_min_bpt_patch_bytes));
    for (std::uint64_t p = 0; p < count; ++p) {
        const std::string name = "patch " + std::to_string(p + 1);
        std::string_view line;
        if (!reader.next(line))
            reader.fail_eof("after " + std::to_string(p) + " of the " + std::to_string(count) +
                            " patches the header announces");
        const auto deg = fields(line, reader);
        if (deg.size() != 2) reader.fail(name + ": expected the degree line '3 3', got " + quote(line));
        const std::uint64_t du = expect_uint(deg[0], reader, name + " degree");
        const std::uint64_t dv = expect_uint(deg[1], reader, name + " degree");
        if (du != 3 || dv != 3)
            reader.fail(name + ": degrees " + std::to_string(du) + " " + std::to_string(dv) +
                        " are not supported (only bicubic patches, '3 3')");
        pool::PatchControlNet net{};
        for (int k = 0; k < 16; ++k) {
            if (!reader.next(line))
                reader.fail_eof("in " + name + " after " + std::to_string(k) + " of its 16 control points");
            net.p[k] = read_point(line, reader, name + " control point " + std::to_string(k + 1));
        }
        set.nets.push_back(net);
    }
    expect_end(reader, "the last patch (the header says " + std::to_string(count) + ")");
    return set;
}

PatchSet parse_newell(std::string_view text, const std::string& label) {
    LineReader reader(text, label);
    PatchSet set;
    set.format = PatchFormat::newell;
    const std::uint64_t count = read_count(reader, "patch count", pool::k_max_patches, "(empty file)");
    std::vector<std::uint32_t> indices;
    std::vector<std::size_t> lines;
    indices.reserve(reserve_count(count, text, k_min_index_line_bytes) * 16);
    lines.reserve(reserve_count(count, text, k_min_index_line_bytes));
    std::string_view line;
    for (std::uint64_t p = 0; p < count; ++p) {
        const std::string name = "patch " + std::to_string(p + 1);
        if (!reader.next(line))
            reader.fail_eof("after " + std::to_string(p) + " of the " + std::to_string(count) +
                            " patches the header announces");
        const auto f = fields(line, reader);
        if (f.size() != 16)
            reader.fail(name + ": expected 16 vertex indices, got " + std::to_string(f.size()));
        lines.push_back(reader.line_number());
        for (int k = 0; k < 16; ++k) {
            const std::uint64_t i = expect_uint(f[k], reader, name + " vertex index");
            if (i == 0) reader.fail(name + ": vertex index 0 (indices are 1-based)");
            indices.push_back(static_cast<std::uint32_t>(std::min<std::uint64_t>(i, 0xffffffffu)));
        }
    }
    const std::uint64_t vcount =
        read_count(reader, "vertex count", std::uint64_t(pool::k_max_patches) * 16, "after the patches");
    std::vector<pool::PatchPoint> vertices;
    vertices.reserve(reserve_count(vcount, text, k_min_vertex_bytes, k_reserve_max * 16));
    for (std::uint64_t v = 0; v < vcount; ++v) {
        if (!reader.next(line))
            reader.fail_eof("after " + std::to_string(v) + " of the " + std::to_string(vcount) +
                            " vertices the header announces");
        vertices.push_back(read_point(line, reader, "vertex " + std::to_string(v + 1)));
    }
    expect_end(reader, "the last vertex (the header says " + std::to_string(vcount) + ")");
    set.nets.resize(count);
    for (std::uint64_t p = 0; p < count; ++p)
        for (int k = 0; k < 16; ++k) {
            const std::uint32_t i = indices[p * 16 + k];
            if (i > vcount)
                reader.fail_at(lines[p], "patch " + std::to_string(p + 1) + ": vertex index " +
                                             std::to_string(i) + " out of range 1.." +
                                             std::to_string(vcount));
            set.nets[p].p[k] = vertices[i - 1];
        }
    return set;
}

/// Content sniffing: a bpt file's second non-blank line is a degree line of two whole numbers.
PatchFormat detect(std::string_view text, const std::string& label) {
    LineReader reader(text, label);
    std::string_view first, second;
    if (!reader.next(first)) reader.fail_eof("(empty file): expected the patch count");
    if (!reader.next(second)) return PatchFormat::newell;  // let the parser report what is missing
    if (second.find(',') != std::string_view::npos) return PatchFormat::newell;
    const auto f = fields(second, reader);
    std::uint64_t a = 0, b = 0;
    if (f.size() == 2 && parse_uint(f[0], a) && parse_uint(f[1], b)) return PatchFormat::bpt;
    return PatchFormat::newell;
}

}  // namespace

PatchFormat parse_patch_format(const std::string& name) {
    if (name == "auto") return PatchFormat::automatic;
    if (name == "bpt") return PatchFormat::bpt;
    if (name == "newell") return PatchFormat::newell;
    throw Error("unknown patch format '" + name + "' (expected auto, bpt or newell)");
}

const char* patch_format_name(PatchFormat format) {
    switch (format) {
        case PatchFormat::automatic:
            return "auto";
        case PatchFormat::bpt:
            return "bpt";
        case PatchFormat::newell:
            return "newell";
    }
    return "unknown";
}

PatchSet parse_patches(std::string_view text, const std::string& label, PatchFormat format) {
    if (format == PatchFormat::automatic) format = detect(text, label);
    return format == PatchFormat::bpt ? parse_bpt(text, label) : parse_newell(text, label);
}

PatchSet read_patch_file(const std::filesystem::path& path, PatchFormat format) {
    const std::string label = path.string();
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) throw Error(label + ": is a folder, not a patch file");
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error(label + ": cannot open: " + std::strerror(errno));
    std::ostringstream ss;
    ss << in.rdbuf();
    if (in.bad()) throw Error(label + ": read error");
    const std::string text = ss.str();
    if (format == PatchFormat::automatic) {
        std::string ext = path.extension().string();
        std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
        if (ext == ".bpt") format = PatchFormat::bpt;
    }
    return parse_patches(text, label, format);
}

}  // namespace prt::patches
