// PointRT prt-import: our own PLY reader (ASCII, binary little and big endian). The vertex element
// becomes a point set; every other element and property is skipped with its size parsed (list
// properties included), so files with faces, range grids or custom data read correctly.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "import.h"

namespace prt::pre::import {

enum class PlyEncoding { ascii, binary_little_endian, binary_big_endian };
enum class PlyType : std::uint8_t { int8, uint8, int16, uint16, int32, uint32, float32, float64 };

/// Bytes of one value of a PLY scalar type.
constexpr std::size_t ply_type_size(PlyType t) {
    switch (t) {
        case PlyType::int8:
        case PlyType::uint8:
            return 1;
        case PlyType::int16:
        case PlyType::uint16:
            return 2;
        case PlyType::int32:
        case PlyType::uint32:
        case PlyType::float32:
            return 4;
        case PlyType::float64:
            return 8;
    }
    return 0;
}

struct PlyProperty {
    std::string name;
    PlyType type = PlyType::float32;  ///< scalar type, or the list's item type
    bool is_list = false;
    PlyType count_type = PlyType::uint8;  ///< lists only: type of the leading item count
};

struct PlyElement {
    std::string name;
    std::uint64_t count = 0;
    std::vector<PlyProperty> properties;
    /// Bytes per row in binary encodings, or 0 when a list property makes rows variable.
    std::size_t fixed_stride() const;
    const PlyProperty* find(std::string_view property) const;
};

struct PlyHeader {
    PlyEncoding encoding = PlyEncoding::ascii;
    std::vector<PlyElement> elements;
    std::size_t data_offset = 0;   ///< first byte after the end_header line
    std::size_t header_lines = 0;  ///< lines up to and including end_header
    const PlyElement* find(std::string_view element) const;
    /// Rows of the "face" element (0 when absent).
    std::uint64_t face_count() const;
    /// Whether the vertex element has nx, ny and nz.
    bool has_vertex_normals() const;
};

const char* ply_encoding_name(PlyEncoding e);

/// Parses the header at the start of `bytes`. Throws prt::Error "LABEL: ..." naming the line.
PlyHeader parse_ply_header(std::string_view bytes, const std::string& label);

/// Reads the vertex element of a PLY file as a point set: x/y/z (any numeric type) -> positions;
/// nx/ny/nz -> normals; red/green/blue[/alpha] -> colors (8-bit integers 0..255, 16-bit 0..65535
/// scaled, floats 0..1; a value outside its range, or a colour property that is a list, is an error
/// naming the vertex); radius -> radii; intensity, scalar_Intensity or reflectance (any case, any
/// numeric type) -> intensities, as the file holds them. A "camera" element of one row with
/// view_px view_py view_pz (VCG / MeshLab, PCL's PLYWriter) gives a point sensor (cloud.sensors).
/// Other properties and elements are skipped and listed once in report.notes. A header declaring
/// more rows than the data holds is an error naming the counts; data after the last declared
/// element is a warning (the header may declare fewer rows than the file holds).
PointCloud read_ply(const std::filesystem::path& path, Report& report, bool quiet);

/// read_ply() streaming (out of core, issue 17): the vertex rows are handed to `flush` in file
/// order, at most `chunk` at a time (the same values read_ply() gives; report.records counts them
/// all), and the pages of the mapped file leave the resident set after each chunk. Returns a point
/// set without points that holds the file's sensor. Throws as read_ply() does (possibly after some
/// chunks were handed over).
PointCloud read_ply_chunks(const std::filesystem::path& path, Report& report, bool quiet, std::size_t chunk,
                           const std::function<void(const PointCloud&)>& flush);

}  // namespace prt::pre::import
