#include "xyz_reader.h"

#include <algorithm>
#include <charconv>
#include <cstring>
#include <functional>
#include <limits>

#include "progress.h"
#include "prt/error.h"
#include "prt/mapped_file.h"
#include "quote.h"

namespace prt::pre::import {

namespace {

inline bool is_separator(char c) {
    return c == ' ' || c == '\t' || c == ',' || c == '\r' || c == ';';
}

/// Parses up to 8 values of one line; returns the count, or -1 when a field is not a number.
int parse_line(const char* p, const char* end, double* values) {
    int n = 0;
    while (true) {
        while (p < end && is_separator(*p)) ++p;
        if (p >= end) return n;
        if (n == 8) return -1;
        const char* start = p;
        while (p < end && !is_separator(*p)) ++p;
        const char* b = start;
        if (*b == '+') ++b;
        double v = 0;
        const auto [ptr, ec] = std::from_chars(b, p, v);
        if (ec == std::errc::result_out_of_range)
            v = std::numeric_limits<double>::infinity();
        else if (ec != std::errc() || ptr != p)
            return -1;
        values[n++] = v;
    }
}

}  // namespace

namespace {

PointCloud read_xyz_impl(const std::filesystem::path& path, Report& report, bool quiet, std::size_t chunk,
                         const std::function<void(const PointCloud&)>* flush) {
    const MappedFile file = MappedFile::open(path);
    const std::string& label = file.label();
    if (file.size() == 0) throw Error(label + ": file is empty");
    if (std::memchr(file.data(), '\0', std::min<std::size_t>(file.size(), 4096)))
        throw Error(label + ": binary data, not XYZ text");

    PointCloud cloud;
    const char* p = file.data();
    const char* const end = p + file.size();
    cloud.positions.reserve(chunk ? std::min<std::size_t>(chunk, file.size() / 24 + 1) : file.size() / 24);
    int columns = 0;  // fixed by the first data line
    std::size_t line = 0;
    std::size_t first_bad = 0;
    std::string first_bad_text;
    std::uint64_t valid = 0;
    LazyProgress progress("reading " + label, file.size(), quiet);
    while (p < end) {
        ++line;
        const char* eol = static_cast<const char*>(std::memchr(p, '\n', static_cast<std::size_t>(end - p)));
        if (!eol) eol = end;
        const char* content_end =
            static_cast<const char*>(std::memchr(p, '#', static_cast<std::size_t>(eol - p)));
        if (!content_end) content_end = eol;
        double v[8];
        const int n = parse_line(p, content_end, v);
        if (n != 0) {
            if (columns == 0 && (n == 3 || n == 6)) {
                columns = n;
                if (columns == 6) cloud.normals.reserve(cloud.positions.capacity());
            }
            if (n == columns) {
                cloud.positions.push_back({v[0], v[1], v[2]});
                if (columns == 6)
                    cloud.normals.push_back(
                        {static_cast<float>(v[3]), static_cast<float>(v[4]), static_cast<float>(v[5])});
                ++valid;
                if (chunk && cloud.size() == chunk) {
                    (*flush)(cloud);
                    cloud.positions.clear();
                    cloud.normals.clear();
                    drop_mapped_pages(file.data(), static_cast<std::size_t>(p - file.data()));
                }
            } else {
                ++report.malformed_lines;
                if (first_bad == 0) {
                    first_bad = line;
                    std::string_view text(p, static_cast<std::size_t>(content_end - p));
                    while (!text.empty() && (text.back() == '\r' || text.back() == ' '))
                        text.remove_suffix(1);
                    first_bad_text = quoted(text, 60);
                }
            }
        }
        p = eol + 1;
        if ((line & 0xFFFF) == 0) progress.update(static_cast<std::uint64_t>(p - file.data()));
    }
    if (chunk && cloud.size() > 0) {
        (*flush)(cloud);
        cloud.positions.clear();
        cloud.normals.clear();
    }
    progress.finish();
    const std::string bad =
        first_bad ? " (first at line " + std::to_string(first_bad) + ": " + first_bad_text + ")" : "";
    if (valid == 0) {
        if (report.malformed_lines == 0) throw Error(label + ": no points (only blank lines and comments)");
        throw Error(label + ": no valid 'x y z' or 'x y z nx ny nz' line; " +
                    std::to_string(report.malformed_lines) + " malformed lines" + bad);
    }
    if (report.malformed_lines > valid)
        throw Error(label + ": not XYZ text: " + std::to_string(report.malformed_lines) + " of " +
                    std::to_string(report.malformed_lines + valid) + " lines are not " +
                    std::to_string(columns) + " numbers" + bad);
    if (report.malformed_lines > 0)
        report.notes.push_back(label + ": dropped " + std::to_string(report.malformed_lines) +
                               " malformed lines (not " + std::to_string(columns) + " numbers)" + bad);
    report.reader = columns == 6 ? "xyz (x y z nx ny nz)" : "xyz (x y z)";
    report.records = valid;
    return cloud;
}

}  // namespace

PointCloud read_xyz(const std::filesystem::path& path, Report& report, bool quiet) {
    return read_xyz_impl(path, report, quiet, 0, nullptr);
}

PointCloud read_xyz_chunks(const std::filesystem::path& path, Report& report, bool quiet, std::size_t chunk,
                           const std::function<void(const PointCloud&)>& flush) {
    return read_xyz_impl(path, report, quiet, std::max<std::size_t>(chunk, 1), &flush);
}

}  // namespace prt::pre::import
