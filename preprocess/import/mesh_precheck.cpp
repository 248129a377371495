// Checks a mesh file's header against its size before OpenMesh reads it: OpenMesh's readers trust
// the counts in a header, and a garbled one can make them loop (almost) forever.
#include <algorithm>
#include <charconv>
#include <cstring>
#include <vector>

#include "mapped_file.h"
#include "mesh.h"
#include "ply_reader.h"
#include "prt/error.h"
#include "quote.h"

namespace prt::pre::import {

namespace {

void check_off(const MappedFile& file) {
    const std::string& label = file.label();
    const std::string_view bytes = file.view();
    std::size_t pos = 0;
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
    const std::string_view magic = token();
    if (magic.size() < 3 || magic.substr(magic.size() - 3) != "OFF")
        throw Error(label + ": not an OFF file (it does not start with OFF, COFF, NOFF, ...)");
    // "nOFF" has a dimension first; "BINARY" OFF keeps its counts in binary: leave those to OpenMesh
    // with only the basic size bound below.
    const std::size_t after_magic = pos;
    const std::string_view next = token();
    if (next == "BINARY" || magic.find('n') != std::string_view::npos) {
        if (bytes.size() - after_magic < 12) throw Error(label + ": OFF file too short for its counts");
        return;
    }
    pos = after_magic;
    std::uint64_t counts[3] = {0, 0, 0};
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
    const std::uint64_t rest = bytes.size() - pos;
    if (counts[0] > rest / 6 || counts[1] > rest / 8)
        throw Error(label + ": OFF header declares " + std::to_string(counts[0]) + " vertices and " +
                    std::to_string(counts[1]) + " faces but the file has only " + std::to_string(rest) +
                    " bytes after the header");

    // The body, line by line as OpenMesh reads it: V vertex lines of at least 3 numbers, then F
    // face lines "n i_1 .. i_n" with n >= 3 and every index a vertex (OpenMesh loops on a
    // negative n and reads out of bounds on a bad index).
    while (pos < bytes.size() && bytes[pos] != '\n') ++pos;  // rest of the counts line
    std::size_t line_no = 1 + static_cast<std::size_t>(std::count(bytes.begin(), bytes.begin() + pos, '\n'));
    auto next_line = [&](std::string_view& line) {
        while (pos < bytes.size()) {
            ++pos;  // past '\n'
            ++line_no;
            const std::size_t e = std::min(bytes.find('\n', pos), bytes.size());
            line = bytes.substr(pos, e - pos);
            pos = e;
            const std::size_t hash = line.find('#');
            if (hash != std::string_view::npos) line = line.substr(0, hash);
            if (line.find_first_not_of(" \t\r") != std::string_view::npos) return true;
        }
        return false;
    };
    auto words = [](std::string_view line) {
        std::vector<std::string_view> w;
        std::size_t i = 0;
        while (i < line.size()) {
            while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
            const std::size_t b = i;
            while (i < line.size() && line[i] != ' ' && line[i] != '\t' && line[i] != '\r') ++i;
            if (i > b) w.push_back(line.substr(b, i - b));
        }
        return w;
    };
    auto where = [&] { return label + ": line " + std::to_string(line_no) + ": "; };
    std::string_view line;
    for (std::uint64_t v = 0; v < counts[0]; ++v) {
        if (!next_line(line))
            throw Error(label + ": OFF header declares " + std::to_string(counts[0]) +
                        " vertices but the file ends after " + std::to_string(v));
        const auto w = words(line);
        if (w.size() < 3)
            throw Error(where() + "vertex " + std::to_string(v) + " has fewer than 3 coordinates");
        for (int k = 0; k < 3; ++k) {
            double x = 0;
            const auto [p, ec] = std::from_chars(w[k].data(), w[k].data() + w[k].size(), x);
            if (ec != std::errc() || p != w[k].data() + w[k].size())
                throw Error(where() + quoted(w[k]) + " is not a number (vertex " + std::to_string(v) + ")");
        }
    }
    for (std::uint64_t f = 0; f < counts[1]; ++f) {
        if (!next_line(line))
            throw Error(label + ": OFF header declares " + std::to_string(counts[1]) +
                        " faces but the file ends after " + std::to_string(f));
        const auto w = words(line);
        std::uint64_t n = 0;
        const auto [p, ec] = std::from_chars(w[0].data(), w[0].data() + w[0].size(), n);
        if (ec != std::errc() || p != w[0].data() + w[0].size() || n < 3 || n + 1 > w.size())
            throw Error(where() + "face " + std::to_string(f) + " is not 'n i_1 .. i_n' with n >= 3");
        for (std::uint64_t k = 1; k <= n; ++k) {
            std::uint64_t idx = 0;
            const auto [q, ec2] = std::from_chars(w[k].data(), w[k].data() + w[k].size(), idx);
            if (ec2 != std::errc() || q != w[k].data() + w[k].size() || idx >= counts[0])
                throw Error(where() + "face " + std::to_string(f) + " has vertex index " + quoted(w[k]) +
                            " (the file has " + std::to_string(counts[0]) + " vertices)");
        }
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

}  // namespace

void precheck_mesh_file(const std::filesystem::path& path) {
    std::string ext = path.extension().string();
    for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (ext == ".ply") {
        Report scratch;  // every element's size checked by our reader
        read_ply(path, scratch, true);
        return;
    }
    const MappedFile file = MappedFile::open(path);
    if (file.size() == 0) throw Error(file.label() + ": file is empty");
    if (ext == ".off")
        check_off(file);
    else if (ext == ".stl")
        check_stl(file);
}

}  // namespace prt::pre::import
