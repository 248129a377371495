// PointRT runtime (host): the frame buffer and image files (PPM/PFM always; PNG, EXR and the other
// formats OpenImageIO knows when built with it).
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "prt/core/scene_view.h"

namespace prt::rt {

/// A rendered frame: linear radiance (RGB floats, row 0 at the top) and its display encoding
/// (RGBA8 after exposure, tone mapping and gamma).
struct Image {
    std::uint32_t width = 0;
    std::uint32_t height = 0;
    std::vector<float> rgb;            ///< width * height * 3
    std::vector<std::uint32_t> rgba8;  ///< width * height, R in the low byte

    void resize(std::uint32_t w, std::uint32_t h) {
        width = w;
        height = h;
        rgb.assign(static_cast<std::size_t>(w) * h * 3, 0.0f);
        rgba8.assign(static_cast<std::size_t>(w) * h, 0u);
    }
};

/// A linear RGB float image read from a file (environment maps).
struct FloatImage {
    std::uint32_t width = 0;
    std::uint32_t height = 0;
    std::vector<float> rgb;
};

/// Whether this build writes `path`'s format (by extension): .ppm and .pfm always; .png, .exr,
/// .jpg, .tif, .hdr ... with OpenImageIO.
bool can_write_image(const std::filesystem::path& path, std::string* why = nullptr);

/// Writes a frame: 8-bit formats (.ppm, .png, .jpg, ...) get the display encoding, float formats
/// (.pfm, .exr, .hdr) the linear radiance times `exposure`. Throws prt::Error naming the file.
void write_image(const std::filesystem::path& path, const Image& image, float exposure = 1.0f);

/// Reads a linear RGB image: .pfm and .ppm (8-bit levels / 255) always, anything OpenImageIO reads
/// when built with it.
/// Throws prt::Error naming the file.
FloatImage read_float_image(const std::filesystem::path& path);

/// Writers and readers of the two formats this project implements itself.
void write_ppm(const std::filesystem::path& path, const Image& image);
void write_pfm(const std::filesystem::path& path, const Image& image, float exposure);
FloatImage read_pfm(const std::filesystem::path& path);

/// Reads a binary PPM (P6, maxval 255) into display-encoded RGBA8 (tests, tools).
Image read_ppm(const std::filesystem::path& path);

/// Whether this build has OpenImageIO.
bool have_oiio();

namespace detail {
// Implemented in image_oiio.cpp (the only file that includes OpenImageIO).
bool oiio_can_write(const std::filesystem::path& path);
void write_oiio(const std::filesystem::path& path, const Image& image, float exposure);
FloatImage read_oiio(const std::filesystem::path& path);
}  // namespace detail

}  // namespace prt::rt
