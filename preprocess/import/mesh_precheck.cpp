// Checks a mesh file's header against its size before OpenMesh reads it: OpenMesh's readers trust
// the counts in a header, and a garbled one can make them loop (almost) forever.
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <vector>

#include "prt/mapped_file.h"
#include "mesh.h"
#include "ply_reader.h"
#include "prt/error.h"
#include "quote.h"

namespace prt::pre::import {

namespace {

/// What an OFF file's magic word says is in it.
struct OffMagic {
    bool colors = false, vertex_normals = false;
    bool dimension = false;  ///< "4OFF" or "nOFF" (other dimensions)
};

/// The first line: the magic word alone. OpenMesh takes the whole first line as the magic line
/// (anything after the magic is ignored), then reads the counts and the body with operator>>, which
/// does not skip '#' comments: a comment, or counts on the magic line, desynchronise it and a stale
/// count can then drive its face loop for billions of iterations (fuzzer). Such files are refused.
OffMagic check_off_magic(const std::string& label, std::string_view bytes, std::size_t line1_end) {
    const std::vector<std::string_view> line1 = split_words(bytes.substr(0, line1_end));
    // The magic as OpenMesh parses it: [ST][C][N][4][n]OFF (it accepts anything after "OFF" on
    // that line, so "OFFnOFF" is a plain OFF to it: the word must be exactly the magic here).
    const std::string_view magic = line1.empty() ? std::string_view() : line1[0];
    std::string_view kind = magic;
    OffMagic m;
    if (kind.substr(0, 2) == "ST") kind.remove_prefix(2);
    if (kind.substr(0, 1) == "C") m.colors = true, kind.remove_prefix(1);
    if (kind.substr(0, 1) == "N") m.vertex_normals = true, kind.remove_prefix(1);
    if (kind.substr(0, 1) == "4") m.dimension = true, kind.remove_prefix(1);
    if (kind.substr(0, 1) == "n") m.dimension = true, kind.remove_prefix(1);
    if (kind != "OFF")
        throw Error(label + ": not an OFF file (its first line does not start with OFF, COFF, NOFF, ...)");
    // Binary OFF: OpenMesh's reader trusts its binary counts (a face count of 2^32 - 1 loops for
    // minutes, a face of 2^32 - 16 corners allocates 16 GiB; fuzzer): not accepted.
    if (line1.size() == 2 && line1[1] == "BINARY")
        throw Error(label + ": binary OFF is not supported (convert it to ASCII OFF or PLY)");
    if (line1.size() > 1)
        throw Error(label + ": line 1: " + quoted(line1[1]) + " after " + quoted(magic) +
                    ": the counts must start on the next line");
    const std::size_t hash = bytes.find('#', line1_end);
    if (hash != std::string_view::npos)
        throw Error(label + ": line " +
                    std::to_string(1 + std::count(bytes.begin(), bytes.begin() + hash, '\n')) +
                    ": '#' comment: the mesh reader (OpenMesh) does not skip comments in OFF files");
    return m;
}

/// The counts line "V F E" from `pos` (left after the counts), checked against the file's size.
void read_off_counts(const std::string& label, std::string_view bytes, std::size_t& pos,
                     std::uint64_t counts[3]) {
    // Next whitespace-separated token, skipping '#' comments.
    auto token = [&]() -> std::string_view {
        while (pos < bytes.size()) {
            const char c = bytes[pos];
            if (c == '#') {
                while (pos < bytes.size() && bytes[pos] != '\n') ++pos;
            } else if (c == ' ' || c == '\t' || c == '\r' || c == '\n') {
                ++pos;
            } else {
                break;
            }
        }
        const std::size_t b = pos;
        while (pos < bytes.size() && bytes[pos] != ' ' && bytes[pos] != '\t' && bytes[pos] != '\r' &&
               bytes[pos] != '\n')
            ++pos;
        return bytes.substr(b, pos - b);
    };
    for (int i = 0; i < 3; ++i) {
        const std::string_view t = token();
        const auto [p, ec] = std::from_chars(t.data(), t.data() + t.size(), counts[i]);
        if (t.empty() || ec != std::errc() || p != t.data() + t.size())
            throw Error(label + ": OFF " +
                        (i == 0   ? "vertex"
                         : i == 1 ? "face"
                                  : "edge") +
                        " count " + quoted(t) + " is not a non-negative integer");
    }
    const std::size_t eol = std::min(bytes.find('\n', pos), bytes.size());
    const std::string_view after = bytes.substr(pos, eol - pos);
    if (after.find_first_not_of(" \t\r") != std::string_view::npos)
        throw Error(label + ": OFF counts line has more than the three counts (vertices faces edges)");
    const std::uint64_t rest = bytes.size() - pos;
    if (counts[0] > rest / 6 || counts[1] > rest / 8)
        throw Error(label + ": OFF header declares " + std::to_string(counts[0]) + " vertices and " +
                    std::to_string(counts[1]) + " faces but the file has only " + std::to_string(rest) +
                    " bytes after the header");
}

/// The body, line by line as OpenMesh reads it: V vertex lines of at least 3 numbers, then F face
/// lines "n i_1 .. i_n" with n >= 3 and every index a vertex (OpenMesh loops on a negative n and
/// reads out of bounds on a bad index).
class OffBody {
public:
    /// `pos` is on the counts line.
    OffBody(const std::string& label, std::string_view bytes, std::size_t pos)
        : m_label(label), m_bytes(bytes) {
        while (pos < bytes.size() && bytes[pos] != '\n') ++pos;  // rest of the counts line
        m_pos = pos;
        m_line_no = 1 + static_cast<std::size_t>(std::count(bytes.begin(), bytes.begin() + pos, '\n'));
    }

    void check_vertices(std::uint64_t count, bool vertex_normals) {
        for (std::uint64_t v = 0; v < count; ++v) {
            const auto w = split_words(record(count, "vertices", v));
            const std::size_t numbers = vertex_normals ? 6 : 3;  // x y z [nx ny nz], read by operator>>
            if (w.size() < numbers)
                throw Error(where() + "vertex " + std::to_string(v) + " has fewer than " +
                            std::to_string(numbers) +
                            (vertex_normals ? " numbers (x y z nx ny nz)" : " coordinates"));
            for (std::size_t k = 0; k < numbers; ++k) {
                double x = 0;
                const auto [p, ec] = std::from_chars(w[k].data(), w[k].data() + w[k].size(), x);
                // operator>> into a float fails on nan, inf and beyond the float range
                // (desynchronising OpenMesh), where from_chars into a double would succeed.
                if (ec != std::errc() || p != w[k].data() + w[k].size() ||
                    !(std::fabs(x) <= std::numeric_limits<float>::max()))
                    throw Error(where() + quoted(w[k]) + " is not a finite float (vertex " +
                                std::to_string(v) + ")");
            }
        }
    }

    void check_faces(std::uint64_t count, std::uint64_t vertices, bool colors) {
        for (std::uint64_t f = 0; f < count; ++f) {
            const auto w = split_words(record(count, "faces", f));
            std::uint64_t n = 0;
            const auto [p, ec] = std::from_chars(w[0].data(), w[0].data() + w[0].size(), n);
            // Without colors OpenMesh reads exactly n + 1 numbers per face: a longer line would
            // feed its extra words to the next face.
            if (ec != std::errc() || p != w[0].data() + w[0].size() || n < 3 || n + 1 > w.size() ||
                (!colors && n + 1 != w.size()))
                throw Error(where() + "face " + std::to_string(f) + " is not 'n i_1 .. i_n' with n >= 3" +
                            (colors ? "" : " (and nothing after it)"));
            for (std::uint64_t k = 1; k <= n; ++k) {
                std::uint64_t idx = 0;
                const auto [q, ec2] = std::from_chars(w[k].data(), w[k].data() + w[k].size(), idx);
                if (ec2 != std::errc() || q != w[k].data() + w[k].size() || idx >= vertices)
                    throw Error(where() + "face " + std::to_string(f) + " has vertex index " + quoted(w[k]) +
                                " (the file has " + std::to_string(vertices) + " vertices)");
            }
        }
    }

private:
    /// The line of record i of `count` (`what`: "vertices" or "faces"); throws when the file ends.
    std::string_view record(std::uint64_t count, const char* what, std::uint64_t i) {
        std::string_view line;
        if (!next_line(line))
            throw Error(m_label + ": OFF header declares " + std::to_string(count) + " " + what +
                        " but the file ends after " + std::to_string(i));
        return line;
    }
    /// The next line with something before a '#' (the comment cut off); false at the end.
    bool next_line(std::string_view& line) {
        while (m_pos < m_bytes.size()) {
            ++m_pos;  // past '\n'
            ++m_line_no;
            const std::size_t e = std::min(m_bytes.find('\n', m_pos), m_bytes.size());
            line = m_bytes.substr(m_pos, e - m_pos);
            m_pos = e;
            const std::size_t hash = line.find('#');
            if (hash != std::string_view::npos) line = line.substr(0, hash);
            if (line.find_first_not_of(" \t\r") != std::string_view::npos) return true;
        }
        return false;
    }
    std::string where() const { return m_label + ": line " + std::to_string(m_line_no) + ": "; }

    const std::string& m_label;
    std::string_view m_bytes;
    std::size_t m_pos = 0, m_line_no = 0;
};

void check_off(const MappedFile& file) {
    const std::string& label = file.label();
    const std::string_view bytes = file.view();
    const std::size_t line1_end = std::min(bytes.find('\n'), bytes.size());
    const OffMagic magic = check_off_magic(label, bytes, line1_end);
    if (magic.dimension) return;  // "4OFF" and "nOFF": OpenMesh refuses them itself
    std::size_t pos = line1_end;
    std::uint64_t counts[3] = {0, 0, 0};
    read_off_counts(label, bytes, pos, counts);
    OffBody body(label, bytes, pos);
    body.check_vertices(counts[0], magic.vertex_normals);
    body.check_faces(counts[1], counts[0], magic.colors);
}

/// OpenMesh's OBJ reader asserts (abort(): Debian builds it with assertions) when the first
/// corner of a face has no vertex index ("f /1 ...", "f //2 ..."; fuzzer), and reads whatever
/// file an mtllib line names. Lines are read as OpenMesh reads them: trimmed, blank and '#' lines
/// skipped, the first word the keyword.
void check_obj(const MappedFile& file) {
    const std::string_view bytes = file.view();
    const auto space = [](char c) {
        return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f';
    };
    std::size_t line_no = 0;
    for (std::size_t pos = 0; pos < bytes.size();) {
        const std::size_t eol = std::min(bytes.find('\n', pos), bytes.size());
        std::string_view line = bytes.substr(pos, eol - pos);
        pos = eol + 1;
        ++line_no;
        while (!line.empty() && (line.front() == ' ' || line.front() == '\t' || line.front() == '\r'))
            line.remove_prefix(1);
        if (line.empty() || line[0] == '#' || space(line[0])) continue;
        std::size_t i = 0;
        while (i < line.size() && !space(line[i])) ++i;
        if (line.substr(0, i) == "mtllib") {
            // OpenMesh opens the OBJ's folder + the rest of the line and reads it line by line:
            // "mtllib ../../dev/zero" grew past 8 GB in 20 s, a FIFO blocks for ever. Only a
            // regular file of a sane size (or none) may be named; materials are not used here.
            std::string_view name = line.substr(i);
            while (!name.empty() && (name.front() == ' ' || name.front() == '\t')) name.remove_prefix(1);
            while (!name.empty() && (name.back() == ' ' || name.back() == '\t' || name.back() == '\r'))
                name.remove_suffix(1);
            const std::string& obj = file.label();
            const std::string material = obj.substr(0, obj.rfind('/') + 1) + std::string(name);
            std::error_code ec;
            const auto st = std::filesystem::status(material, ec);
            if (!ec && std::filesystem::exists(st) &&
                (!std::filesystem::is_regular_file(st) ||
                 std::filesystem::file_size(material, ec) > (64u << 20)))
                throw Error(obj + ": line " + std::to_string(line_no) + ": mtllib names " + quoted(name) +
                            ", which is not a material file (not a regular file, or over 64 MiB)");
            continue;
        }
        if (line.substr(0, i) != "f") continue;
        while (i < line.size() && space(line[i])) ++i;
        std::size_t e = i;
        while (e < line.size() && !space(line[e])) ++e;
        const std::string_view corner = line.substr(i, e - i);
        if (corner.empty()) continue;  // "f" alone: OpenMesh skips it
        const std::string_view vertex = corner.substr(0, corner.find('/'));
        int index = 0;
        const auto [p, ec] = std::from_chars(vertex.data(), vertex.data() + vertex.size(), index);
        if (vertex.empty() || ec != std::errc() || p != vertex.data() + vertex.size())
            throw Error(file.label() + ": line " + std::to_string(line_no) + ": face corner " +
                        quoted(corner) + " has no vertex index");
    }
}

void check_stl(const MappedFile& file) {
    const std::string_view bytes = file.view();
    if (bytes.size() >= 84) {
        std::uint32_t n = 0;
        std::memcpy(&n, bytes.data() + 80, 4);
        if (84 + 50 * static_cast<std::uint64_t>(n) == bytes.size()) return;  // binary STL
    }
    const std::size_t first = bytes.find_first_not_of(" \t\r\n");
    if (first != std::string_view::npos && bytes.substr(first, 5) == "solid") return;  // ASCII STL
    throw Error(file.label() +
                ": not an STL file (neither ASCII starting with 'solid' nor binary with a triangle "
                "count matching the file size)");
}

// ---- PLY meshes: what OpenMesh 9.0's PLY reader can read without losing its place -----------
//
// OpenMesh parses the header with operator>> and loops until "end_header" checking only bad(): a
// failed read (a version or count that is not a number, a control byte splitting a word) loops
// forever, printing and growing memory. Its data readers consume only the types they convert
// (binary integer coordinates and double colors are not consumed), skip a list outside "face" as a
// single value, drop face properties declared before vertex_indices, and find binary data 12 bytes
// after the last header word: any of these desynchronises it, and a face corner count read from
// the wrong bytes can then drive a loop of up to 2^32 push_backs. The fuzzer (prt-fuzz-ply-mesh)
// found the version and control-byte hangs; the layouts were then checked one by one against the
// installed OpenMesh 9.0. Our reader has already checked every element's size; this refuses the
// layouts OpenMesh would misread.

bool is_float_word(std::string_view w) {
    double x = 0;
    const auto [p, ec] = std::from_chars(w.data(), w.data() + w.size(), x);
    return !w.empty() && ec == std::errc() && p == w.data() + w.size() &&
           std::fabs(x) <= std::numeric_limits<float>::max();  // operator>> fails on nan, inf, overflow
}

bool is_integer_word(std::string_view w, std::int64_t lo, std::int64_t hi) {
    std::int64_t x = 0;
    const auto [p, ec] = std::from_chars(w.data(), w.data() + w.size(), x);
    return !w.empty() && ec == std::errc() && p == w.data() + w.size() && x >= lo && x <= hi;
}

/// How OpenMesh reads one property: into a float (coordinates, normals, texture coordinates,
/// float colors), into an int (integer colors), or skipped.
enum class OmRead { skip, as_float, as_int };

bool is_color(const std::string& element, const std::string& name) {
    if (element == "vertex" && (name == "diffuse_red" || name == "diffuse_green" || name == "diffuse_blue"))
        return true;
    return (element == "vertex" || element == "face") &&
           (name == "red" || name == "green" || name == "blue" || name == "alpha");
}

OmRead om_read(const std::string& element, const PlyProperty& p) {
    static constexpr const char* k_float_vertex[] = {"x", "y", "z", "nx", "ny", "nz", "u", "s", "v", "t"};
    if (element == "vertex")
        for (const char* n : k_float_vertex)
            if (p.name == n) return OmRead::as_float;
    if (is_color(element, p.name)) return p.type == PlyType::float32 ? OmRead::as_float : OmRead::as_int;
    return OmRead::skip;
}

void check_ply_for_openmesh(const MappedFile& file) {
    const std::string& label = file.label();
    const std::string_view bytes = file.view();
    const PlyHeader header = parse_ply_header(bytes, label);
    const std::size_t end = header.data_offset;
    std::size_t line = 1;
    for (std::size_t i = 0; i < end; ++i) {
        const auto c = static_cast<unsigned char>(bytes[i]);
        if (c == '\n')
            ++line;
        else if ((c < 0x20 && c != '\t' && c != '\r') || c == 0x7F)
            throw Error(label + ": line " + std::to_string(line) + ": control byte " + std::to_string(c) +
                        " in the PLY header (a header is text)");
    }
    auto refuse = [&](const std::string& what) {
        throw Error(label + ": " + what + " (the mesh reader, OpenMesh, cannot read this PLY layout)");
    };
    // Header words as OpenMesh reads them.
    line = 0;
    for (std::size_t pos = 0; pos < end;) {
        const std::size_t eol = std::min(bytes.find('\n', pos), end);
        const std::string_view text = bytes.substr(pos, eol - pos);
        pos = eol + 1;
        ++line;
        std::vector<std::string_view> w;
        for (std::size_t i = 0; i < text.size();) {
            while (i < text.size() && (text[i] == ' ' || text[i] == '\t' || text[i] == '\r')) ++i;
            const std::size_t b = i;
            while (i < text.size() && text[i] != ' ' && text[i] != '\t' && text[i] != '\r') ++i;
            if (i > b) w.push_back(text.substr(b, i - b));
        }
        if (w.empty()) continue;
        const std::string where = "line " + std::to_string(line) + ": ";
        if (w[0] == "format" && w.size() == 3 && !is_float_word(w[2]))
            refuse(where + "version " + quoted(w[2]) + " is not a plain number");
        if (w[0] == "element" && w.size() == 3 && !is_integer_word(w[2], 0, 0xFFFFFFFFll))
            refuse(where + "element count " + quoted(w[2]) + " above 4294967295");
        if (w[0] == "obj_info")
            for (const std::string_view word : w)
                if (word == "element" || word == "property" || word == "comment" || word == "end_header")
                    refuse(where + "obj_info containing the keyword " + quoted(word));
    }
    int vertex_elements = 0, face_elements = 0;
    for (const PlyElement& el : header.elements) {
        vertex_elements += el.name == "vertex";
        face_elements += el.name == "face";
        for (std::size_t k = 0; k < el.properties.size(); ++k) {
            const PlyProperty& p = el.properties[k];
            const std::string what = "element '" + el.name + "', property '" + p.name + "': ";
            if (p.is_list) {
                if (el.name != "face" || (p.name != "vertex_indices" && p.name != "vertex_index") || k != 0)
                    refuse(what + "a list other than the first face property vertex_indices");
                if (p.type == PlyType::float32 || p.type == PlyType::float64)
                    refuse(what + "vertex indices that are not integers");
                continue;
            }
            // OpenMesh 9.0 converts double colors to an integer it cannot make (the bytes stay
            // unread) and reads a double color's text as an int.
            if (is_color(el.name, p.name) && p.type == PlyType::float64) refuse(what + "a double color");
            // Binary integer coordinates: "unsupported conversion type to float", bytes unread.
            if (header.encoding != PlyEncoding::ascii && om_read(el.name, p) == OmRead::as_float &&
                p.type != PlyType::float32 && p.type != PlyType::float64)
                refuse(what + "binary coordinates or normals that are not float or double");
        }
    }
    if (vertex_elements > 1 || face_elements > 1) refuse("more than one vertex or face element");
    if (header.encoding != PlyEncoding::ascii) {
        // OpenMesh finds the binary data at the last header word + "\nend_header\n" (12 bytes, 14
        // with "\r\n"): the header must end exactly so.
        const std::string_view head = bytes.substr(0, end);
        const bool lf = head.size() > 12 && head.substr(head.size() - 12) == "\nend_header\n" &&
                        head[head.size() - 13] != ' ' && head[head.size() - 13] != '\t' &&
                        head[head.size() - 13] != '\r' && head[head.size() - 13] != '\n';
        const bool crlf = head.size() > 14 && head.substr(head.size() - 14) == "\r\nend_header\r\n" &&
                          head[head.size() - 15] != ' ' && head[head.size() - 15] != '\t' &&
                          head[head.size() - 15] != '\r' && head[head.size() - 15] != '\n';
        if (!lf && !crlf) refuse("binary header not ending in exactly 'end_header' after the last property");
        return;
    }
    // ASCII data: every value OpenMesh converts must be a number operator>> reads whole (a failed
    // read leaves a stale corner count for the following faces).
    std::size_t pos = end;
    line = header.header_lines;
    auto next = [&](std::string_view& tok) {
        while (pos < bytes.size() &&
               (bytes[pos] == ' ' || bytes[pos] == '\t' || bytes[pos] == '\r' || bytes[pos] == '\n')) {
            line += bytes[pos] == '\n';
            ++pos;
        }
        const std::size_t b = pos;
        while (pos < bytes.size() && bytes[pos] != ' ' && bytes[pos] != '\t' && bytes[pos] != '\r' &&
               bytes[pos] != '\n')
            ++pos;
        tok = bytes.substr(b, pos - b);
        return !tok.empty();
    };
    auto bad = [&](std::string_view tok, const char* what) {
        refuse("line " + std::to_string(line + 1) + ": " + quoted(tok) + " is not " + what);
    };
    std::string_view tok;
    for (const PlyElement& el : header.elements) {
        for (std::uint64_t row = 0; row < el.count; ++row) {
            for (const PlyProperty& p : el.properties) {
                if (!next(tok)) return;  // our reader already reported a short file
                if (p.is_list) {
                    if (!is_integer_word(tok, 0, 0xFFFFFFFFll)) bad(tok, "a corner count");
                    std::uint64_t n = 0;
                    std::from_chars(tok.data(), tok.data() + tok.size(), n);
                    for (std::uint64_t j = 0; j < n; ++j) {
                        if (!next(tok)) return;
                        if (!is_integer_word(tok, 0, 0xFFFFFFFFll)) bad(tok, "a vertex index");
                    }
                    continue;
                }
                switch (om_read(el.name, p)) {
                    case OmRead::as_float:
                        if (!is_float_word(tok)) bad(tok, "a finite float");
                        break;
                    case OmRead::as_int:
                        if (!is_integer_word(tok, -2147483648ll, 2147483647ll)) bad(tok, "an integer");
                        break;
                    case OmRead::skip:
                        break;
                }
            }
        }
        if (el.name == "face") return;  // OpenMesh stops after the faces
    }
}

}  // namespace

void precheck_mesh_file(const std::filesystem::path& path) {
    std::string ext = path.extension().string();
    for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (ext == ".ply") {
        Report scratch;  // every element's size checked by our reader
        read_ply(path, scratch, true);
        check_ply_for_openmesh(MappedFile::open(path));
        return;
    }
    const MappedFile file = MappedFile::open(path);
    if (file.size() == 0) throw Error(file.label() + ": file is empty");
    if (ext == ".off")
        check_off(file);
    else if (ext == ".obj")
        check_obj(file);
    else if (ext == ".stl")
        check_stl(file);
}

}  // namespace prt::pre::import
