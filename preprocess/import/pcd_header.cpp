#include "pcd_header.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <set>

#include "prt/mapped_file.h"
#include "poses.h"
#include "prt/error.h"
#include "quote.h"

namespace prt::pre::import {

namespace {

bool to_u64(std::string_view s, std::uint64_t& v) {
    const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    return ec == std::errc() && p == s.data() + s.size();
}

[[noreturn]] void header_fail(const std::string& label, std::size_t line_no, const std::string& what) {
    throw Error(label + ": not a valid PCD file: line " + std::to_string(line_no) + ": " + what);
}

/// The header's lines up to DATA, keyword by keyword (each keyword once).
class HeaderParser {
public:
    explicit HeaderParser(const std::string& label) : m_label(label) {}

    /// Reads the header from `bytes` into `h`; returns the offset after the DATA line.
    std::size_t parse(std::string_view bytes, PcdHeader& h) {
        constexpr std::size_t k_max_header = 1u << 16;  // a real PCD header is a few hundred bytes
        std::size_t pos = 0;
        while (h.data.empty()) {
            if (pos >= bytes.size() || pos > k_max_header)
                throw Error(m_label + ": not a valid PCD file (no DATA line in the header)");
            const std::size_t eol = bytes.find('\n', pos);
            const std::string_view line =
                bytes.substr(pos, (eol == std::string_view::npos ? bytes.size() : eol) - pos);
            pos = eol == std::string_view::npos ? bytes.size() : eol + 1;
            ++line_no;
            if (line.find('\0') != std::string_view::npos) fail("binary bytes in the header");
            const auto w = split_words(line);
            // PCL skips empty lines but crashes (a null read in PCDReader::read, PCL 1.13) on a line
            // of only spaces, tabs or a carriage return before FIELDS: such lines are refused (fuzzer).
            if (w.empty() && !line.empty()) fail("a blank line of spaces, tabs or a carriage return");
            if (w.empty() || w[0][0] == '#') continue;
            keyword(w, h);
        }
        return pos;
    }

    std::size_t line_no = 0;
    bool have_width = false, have_height = false, have_points = false, have_count = false;

private:
    [[noreturn]] void fail(const std::string& what) const { header_fail(m_label, line_no, what); }

    /// One header line: keyword w[0] and its values.
    void keyword(const std::vector<std::string_view>& w, PcdHeader& h) {
        const std::string_view key = w[0];
        // PCL acts on every header line as it comes (POINTS 14294967296 then POINTS 4: it sized
        // its buffer from the first, 400 GB; fuzzer); ours kept the last. Each keyword once.
        const std::string canonical = key == "COLUMNS" ? std::string("FIELDS") : std::string(key);
        if (!m_seen.insert(canonical).second) fail(canonical + " given twice");
        auto unsigned_list = [&](std::vector<std::uint32_t>& out) {
            for (std::size_t i = 1; i < w.size(); ++i) {
                std::uint64_t v = 0;
                if (!to_u64(w[i], v) || v > 0xFFFFFFFFu) fail(quoted(w[i], 20) + " is not a count");
                out.push_back(static_cast<std::uint32_t>(v));
            }
        };
        auto single = [&](std::uint64_t& out, bool& seen) {
            if (w.size() != 2 || !to_u64(w[1], out)) fail(std::string(key) + " needs one unsigned number");
            seen = true;
        };
        if (key == "VERSION") {
        } else if (key == "FIELDS" || key == "COLUMNS") {
            for (std::size_t i = 1; i < w.size(); ++i) h.fields.emplace_back(w[i]);
        } else if (key == "SIZE") {
            unsigned_list(h.size);
        } else if (key == "TYPE") {
            for (std::size_t i = 1; i < w.size(); ++i) {
                if (w[i].size() != 1 || std::strchr("IUF", w[i][0]) == nullptr)
                    fail("TYPE " + quoted(w[i], 20) + " is not I, U or F");
                h.type.push_back(w[i][0]);
            }
        } else if (key == "COUNT") {
            unsigned_list(h.count);
            have_count = true;
        } else if (key == "WIDTH") {
            single(h.width, have_width);
        } else if (key == "HEIGHT") {
            single(h.height, have_height);
        } else if (key == "POINTS") {
            single(h.points, have_points);
        } else if (key == "VIEWPOINT") {
            h.viewpoint = viewpoint(w);
        } else if (key == "DATA") {
            if (w.size() != 2 || (w[1] != "ascii" && w[1] != "binary" && w[1] != "binary_compressed"))
                fail("DATA must be ascii, binary or binary_compressed");
            h.data = std::string(w[1]);
        } else {
            fail("unknown header keyword " + quoted(key));
        }
    }

    /// VIEWPOINT tx ty tz qw qx qy qz: finite numbers, the quaternion of norm 1 (normalised).
    std::array<double, 7> viewpoint(const std::vector<std::string_view>& w) const {
        if (w.size() != 8)
            fail("VIEWPOINT needs 7 numbers (tx ty tz qw qx qy qz), got " + std::to_string(w.size() - 1));
        std::array<double, 7> v{};
        for (int i = 0; i < 7; ++i) {
            const std::string_view word = w[1 + i];
            const char* b = word.data();
            const char* e = b + word.size();
            if (b < e && *b == '+') ++b;
            const auto [p, ec] = std::from_chars(b, e, v[i]);
            if (ec != std::errc() || p != e || !std::isfinite(v[i]))
                fail("VIEWPOINT value " + quoted(word, 20) + " is not a finite number");
        }
        const double norm = std::sqrt(v[3] * v[3] + v[4] * v[4] + v[5] * v[5] + v[6] * v[6]);
        if (std::fabs(norm - 1.0) > k_quaternion_tolerance) {
            char buf[128];
            std::snprintf(buf, sizeof buf,
                          "VIEWPOINT quaternion (qw qx qy qz) has norm %.6g, not 1 (within %g)", norm,
                          k_quaternion_tolerance);
            fail(buf);
        }
        for (int i = 3; i < 7; ++i) v[i] /= norm;
        return v;
    }

    const std::string& m_label;
    std::set<std::string> m_seen;  // header keywords met so far
};

/// PCL's header reader goes on past DATA while lines look like header lines (a keyword prefix or a
/// '#' comment; empty lines skipped) and takes the last DATA and POINTS it sees: a POINTS
/// 34294967296 after "DATA ascii" made it allocate 548 GB (fuzzer). Refused here.
void refuse_header_after_data(const std::string& label, std::string_view bytes, std::size_t pos,
                              std::size_t line_no) {
    for (std::size_t p = pos; p < bytes.size();) {
        const std::size_t e = std::min(bytes.find('\n', p), bytes.size());
        const auto w = split_words(bytes.substr(p, e - p));
        if (e == p) {
            p = e + 1;
            continue;
        }
        static constexpr const char* k_keywords[] = {"#",      "VERSION",   "FIELDS", "COLUMNS",
                                                     "SIZE",   "TYPE",      "COUNT",  "WIDTH",
                                                     "HEIGHT", "VIEWPOINT", "POINTS", "DATA"};
        for (const char* k : k_keywords)
            if (!w.empty() && w[0].substr(0, std::strlen(k)) == k) {
                line_no +=
                    1 + static_cast<std::size_t>(std::count(bytes.begin() + pos, bytes.begin() + p, '\n'));
                header_fail(label, line_no, "header line " + quoted(w[0], 20) + " after the DATA line");
            }
        break;
    }
}

/// The fields (FIELDS, SIZE, TYPE and COUNT agree; sizes, packed colours, intensity) and the point
/// count (WIDTH x HEIGHT = POINTS, defaults filled in); sets point_step.
void check_layout(const std::string& label, const HeaderParser& parsed, PcdHeader& h) {
    if (h.fields.empty()) throw Error(label + ": not a valid PCD file (no FIELDS line)");
    if (!parsed.have_count) h.count.assign(h.fields.size(), 1);
    if (h.size.size() != h.fields.size() || h.type.size() != h.fields.size() ||
        h.count.size() != h.fields.size())
        throw Error(label + ": not a valid PCD file (FIELDS, SIZE, TYPE and COUNT list " +
                    std::to_string(h.fields.size()) + ", " + std::to_string(h.size.size()) + ", " +
                    std::to_string(h.type.size()) + " and " + std::to_string(h.count.size()) + " entries)");
    for (std::size_t i = 0; i < h.fields.size(); ++i) {
        const std::uint32_t s = h.size[i];
        if (s != 1 && s != 2 && s != 4 && s != 8)
            throw Error(label + ": not a valid PCD file (field " + h.fields[i] + " has SIZE " +
                        std::to_string(s) + ")");
        if (h.type[i] == 'F' && s != 4 && s != 8)
            throw Error(label + ": not a valid PCD file (float field " + h.fields[i] + " has SIZE " +
                        std::to_string(s) + ")");
        h.point_step += static_cast<std::uint64_t>(s) * h.count[i];
        // Colours are PCL's packed 0x00RRGGBB / 0xAARRGGBB in one 4-byte float or integer.
        if ((h.fields[i] == "rgb" || h.fields[i] == "rgba") && (s != 4 || h.count[i] != 1))
            throw Error(label + ": PCD field " + h.fields[i] + " has SIZE " + std::to_string(s) +
                        " and COUNT " + std::to_string(h.count[i]) +
                        "; a packed colour is one 4-byte value per point (SIZE 4, COUNT 1)");
        if (h.fields[i] == "intensity" && h.count[i] != 1)
            throw Error(label + ": PCD field intensity has COUNT " + std::to_string(h.count[i]) +
                        "; intensity is one value per point (COUNT 1)");
    }
    if (!parsed.have_width) throw Error(label + ": not a valid PCD file (no WIDTH line)");
    if (!parsed.have_height) h.height = 1;
    if (!parsed.have_points) h.points = h.width * h.height;
    // PCL keeps WIDTH and HEIGHT in 32 bits; within that their product cannot overflow 64 bits.
    if (h.width > 0xFFFFFFFFull || h.height > 0xFFFFFFFFull)
        throw Error(label + ": not a valid PCD file (WIDTH " + std::to_string(h.width) + " x HEIGHT " +
                    std::to_string(h.height) + ": each must be at most 4294967295)");
    if (h.width == 0 || h.height == 0 || h.points != h.width * h.height)
        throw Error(label + ": not a valid PCD file (POINTS " + std::to_string(h.points) + " is not WIDTH " +
                    std::to_string(h.width) + " x HEIGHT " + std::to_string(h.height) + ")");
}

/// binary: the data holds the declared points (a note for bytes after them).
void check_binary(const std::string& label, const PcdHeader& h, std::uint64_t available, Report& report) {
    // Compared by division: points x point_step can overflow 64 bits (2^31 x 2^31 x 12 = 0).
    if (h.point_step == 0 || h.points > available / h.point_step)
        throw Error(label + ": header declares " + std::to_string(h.points) +
                    " points but the data ends after " +
                    std::to_string(h.point_step ? available / h.point_step : 0));
    const std::uint64_t need = h.points * h.point_step;
    if (available > need)
        report.notes.push_back(
            label + ": warning: " + std::to_string(available - need) +
            " bytes after the declared points (the header may declare fewer points than the "
            "file holds; not read)");
}

/// binary_compressed: the size words agree with the header and with what LZF can do.
void check_compressed(const std::string& label, const PcdHeader& h, std::string_view bytes,
                      std::uint64_t available) {
    if (available < 8) throw Error(label + ": binary_compressed data is truncated (no size words)");
    std::uint32_t compressed = 0, uncompressed = 0;
    std::memcpy(&compressed, bytes.data() + h.data_offset, 4);
    std::memcpy(&uncompressed, bytes.data() + h.data_offset + 4, 4);
    const bool fits = h.point_step == 0 || h.points <= 0xFFFFFFFFull / h.point_step;  // no overflow
    if (!fits || uncompressed != h.points * h.point_step)
        throw Error(label + ": binary_compressed data unpacks to " + std::to_string(uncompressed) +
                    " bytes but the header declares " + std::to_string(h.points) + " points of " +
                    std::to_string(h.point_step) + " bytes");
    // LZF cannot compress better than about 1:130 (a 3-byte back-reference covers at most 264
    // bytes): a larger claim is a lie, and PCL would allocate it before finding out.
    if (uncompressed > 150ull * compressed + 4096)
        throw Error(label + ": binary_compressed data claims " + std::to_string(uncompressed) +
                    " bytes from " + std::to_string(compressed) + " compressed bytes");
    if (available - 8 < compressed)
        throw Error(label + ": binary_compressed data is truncated (" + std::to_string(available - 8) +
                    " of " + std::to_string(compressed) + " bytes)");
}

/// ascii: one point per non-blank line, and room for every value (a note for lines after them).
void check_ascii(const std::string& label, const PcdHeader& h, std::string_view bytes,
                 std::uint64_t available, Report& report) {
    std::uint64_t lines = 0;
    std::size_t p = h.data_offset;
    while (p < bytes.size()) {
        std::size_t e = bytes.find('\n', p);
        if (e == std::string_view::npos) e = bytes.size();
        if (bytes.substr(p, e - p).find_first_not_of(" \t\r") != std::string_view::npos) ++lines;
        p = e + 1;
    }
    if (lines < h.points)
        throw Error(label + ": header declares " + std::to_string(h.points) + " points but the data has " +
                    std::to_string(lines) + " lines");
    // Every value takes at least one byte, so the data bounds POINTS x the values per point; PCL
    // allocates POINTS x point_step before reading (COUNT 77777771 for one field of 4 points:
    // 2.5 GB, fuzzer).
    std::uint64_t values = 0;
    for (const std::uint32_t c : h.count) values += c;
    if (values > 0 && h.points > available / values)
        throw Error(label + ": header declares " + std::to_string(h.points) + " points of " +
                    std::to_string(values) + " values (COUNT) but the data holds only " +
                    std::to_string(available) + " bytes");
    if (lines > h.points)
        report.notes.push_back(label + ": warning: " + std::to_string(lines - h.points) +
                               " lines after the declared points (not read)");
}

}  // namespace

PcdHeader check_pcd(const MappedFile& file, Report& report) {
    const std::string& label = file.label();
    const std::string_view bytes = file.view();
    if (bytes.empty()) throw Error(label + ": file is empty");
    PcdHeader h;
    HeaderParser parser(label);
    h.data_offset = parser.parse(bytes, h);
    refuse_header_after_data(label, bytes, h.data_offset, parser.line_no);
    check_layout(label, parser, h);
    const std::uint64_t available = bytes.size() - h.data_offset;
    if (h.data == "binary")
        check_binary(label, h, available, report);
    else if (h.data == "binary_compressed")
        check_compressed(label, h, bytes, available);
    else
        check_ascii(label, h, bytes, available, report);
    return h;
}

}  // namespace prt::pre::import
