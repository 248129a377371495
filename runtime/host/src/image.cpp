#include "prt/runtime/image.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>

#include "prt/atomic_file.h"
#include "prt/error.h"

namespace prt::rt {

namespace {

std::string lower_extension(const std::filesystem::path& p) {
    std::string e = p.extension().string();
    std::transform(e.begin(), e.end(), e.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return e;
}

bool is_float_format(const std::string& ext) {
    return ext == ".pfm" || ext == ".exr" || ext == ".hdr";
}

void check_image(const std::filesystem::path& path, const Image& image) {
    const std::size_t n = static_cast<std::size_t>(image.width) * image.height;
    if (image.width == 0 || image.height == 0 || image.rgb.size() != n * 3 || image.rgba8.size() != n) {
        throw Error(path.string() + ": internal error: image buffers do not match " +
                    std::to_string(image.width) + "x" + std::to_string(image.height));
    }
}

}  // namespace

bool have_oiio() {
#ifdef PRT_HAVE_OIIO
    return true;
#else
    return false;
#endif
}

bool can_write_image(const std::filesystem::path& path, std::string* why) {
    const std::string ext = lower_extension(path);
    if (ext == ".ppm" || ext == ".pfm") return true;
    if (ext.empty()) {
        if (why) *why = path.string() + ": no file extension (use .png, .exr, .ppm or .pfm)";
        return false;
    }
    if (have_oiio()) {
        if (detail::oiio_can_write(path)) return true;
        if (why)
            *why = path.string() + ": no image writer for '" + ext +
                   "' (OpenImageIO has none; try .png, .exr, .ppm or .pfm)";
        return false;
    }
    if (why) {
        *why = path.string() + ": this build has no OpenImageIO, so it writes only .ppm and .pfm (not " +
               ext + ")";
    }
    return false;
}

void write_ppm(const std::filesystem::path& path, const Image& image) {
    check_image(path, image);
    AtomicFile f(path);
    const std::string header =
        "P6\n" + std::to_string(image.width) + " " + std::to_string(image.height) + "\n255\n";
    f.write(header.data(), header.size());
    std::vector<unsigned char> row(static_cast<std::size_t>(image.width) * 3);
    for (std::uint32_t y = 0; y < image.height; ++y) {
        for (std::uint32_t x = 0; x < image.width; ++x) {
            const std::uint32_t p = image.rgba8[static_cast<std::size_t>(y) * image.width + x];
            row[x * 3 + 0] = static_cast<unsigned char>(p & 0xff);
            row[x * 3 + 1] = static_cast<unsigned char>((p >> 8) & 0xff);
            row[x * 3 + 2] = static_cast<unsigned char>((p >> 16) & 0xff);
        }
        f.write(row.data(), row.size());
    }
    f.commit();
}

void write_pfm(const std::filesystem::path& path, const Image& image, float exposure) {
    check_image(path, image);
    AtomicFile f(path);
    // PFM: "PF", size, scale (negative = little-endian), rows bottom to top.
    const std::string header =
        "PF\n" + std::to_string(image.width) + " " + std::to_string(image.height) + "\n-1.0\n";
    f.write(header.data(), header.size());
    std::vector<float> row(static_cast<std::size_t>(image.width) * 3);
    for (std::uint32_t y = image.height; y-- > 0;) {
        const float* src = image.rgb.data() + static_cast<std::size_t>(y) * image.width * 3;
        for (std::size_t i = 0; i < row.size(); ++i) row[i] = src[i] * exposure;
        f.write(row.data(), row.size() * sizeof(float));
    }
    f.commit();
}

namespace {

/// Reads the whitespace-separated header tokens of a PNM/PFM file.
std::string read_token(std::istream& in) {
    std::string t;
    char c;
    while (in.get(c)) {
        if (c == '#') {
            std::string line;
            std::getline(in, line);
            continue;
        }
        if (std::isspace(static_cast<unsigned char>(c))) {
            if (!t.empty()) break;
            continue;
        }
        t.push_back(c);
    }
    return t;
}

std::uint32_t parse_size(const std::filesystem::path& path, const std::string& t, const char* what) {
    try {
        std::size_t used = 0;
        const unsigned long v = std::stoul(t, &used);
        if (used != t.size() || v == 0 || v > 65536) throw std::out_of_range(what);
        return static_cast<std::uint32_t>(v);
    } catch (const std::exception&) {
        throw Error(path.string() + ": bad " + what + " '" + t + "' in the header");
    }
}

}  // namespace

FloatImage read_pfm(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error(path.string() + ": cannot open");
    const std::string magic = read_token(in);
    if (magic != "PF" && magic != "Pf")
        throw Error(path.string() + ": not a PFM file (magic '" + magic + "')");
    const bool color = magic == "PF";
    FloatImage img;
    img.width = parse_size(path, read_token(in), "width");
    img.height = parse_size(path, read_token(in), "height");
    const std::string scale_text = read_token(in);
    double scale = 0;
    try {
        scale = std::stod(scale_text);
    } catch (const std::exception&) {
        throw Error(path.string() + ": bad scale '" + scale_text + "' in the header");
    }
    if (scale == 0 || !std::isfinite(scale))
        throw Error(path.string() + ": bad scale '" + scale_text + "' in the header");
    if (scale > 0) throw Error(path.string() + ": big-endian PFM is not supported");
    const std::size_t channels = color ? 3 : 1;
    std::vector<float> data(static_cast<std::size_t>(img.width) * img.height * channels);
    in.read(reinterpret_cast<char*>(data.data()), static_cast<std::streamsize>(data.size() * sizeof(float)));
    if (static_cast<std::size_t>(in.gcount()) != data.size() * sizeof(float))
        throw Error(path.string() + ": truncated pixel data");
    img.rgb.resize(static_cast<std::size_t>(img.width) * img.height * 3);
    std::uint64_t bad = 0;
    for (std::uint32_t y = 0; y < img.height; ++y) {
        const std::uint32_t src_row = img.height - 1 - y;  // PFM rows run bottom to top
        for (std::uint32_t x = 0; x < img.width; ++x) {
            for (std::size_t c = 0; c < 3; ++c) {
                float v = data[(static_cast<std::size_t>(src_row) * img.width + x) * channels +
                               (channels == 3 ? c : 0)];
                if (!std::isfinite(v)) {
                    v = 0;
                    ++bad;
                }
                img.rgb[(static_cast<std::size_t>(y) * img.width + x) * 3 + c] = v;
            }
        }
    }
    (void)bad;
    return img;
}

Image read_ppm(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error(path.string() + ": cannot open");
    if (read_token(in) != "P6") throw Error(path.string() + ": not a binary PPM (P6) file");
    Image img;
    const std::uint32_t w = parse_size(path, read_token(in), "width");
    const std::uint32_t h = parse_size(path, read_token(in), "height");
    if (read_token(in) != "255") throw Error(path.string() + ": only maxval 255 is supported");
    img.resize(w, h);
    std::vector<unsigned char> data(static_cast<std::size_t>(w) * h * 3);
    in.read(reinterpret_cast<char*>(data.data()), static_cast<std::streamsize>(data.size()));
    if (static_cast<std::size_t>(in.gcount()) != data.size())
        throw Error(path.string() + ": truncated pixel data");
    for (std::size_t i = 0; i < static_cast<std::size_t>(w) * h; ++i) {
        img.rgba8[i] = data[i * 3] | (data[i * 3 + 1] << 8) | (data[i * 3 + 2] << 16) | (255u << 24);
        for (int c = 0; c < 3; ++c) img.rgb[i * 3 + c] = data[i * 3 + c] / 255.0f;
    }
    return img;
}

void write_image(const std::filesystem::path& path, const Image& image, float exposure) {
    check_image(path, image);
    std::string why;
    if (!can_write_image(path, &why)) throw Error(why);
    const std::string ext = lower_extension(path);
    if (ext == ".ppm") return write_ppm(path, image);
    if (ext == ".pfm") return write_pfm(path, image, exposure);
    detail::write_oiio(path, image, is_float_format(ext) ? exposure : 1.0f);
}

FloatImage read_float_image(const std::filesystem::path& path) {
    const std::string ext = lower_extension(path);
    if (ext == ".pfm") return read_pfm(path);
    if (ext == ".ppm") {
        // 8-bit levels over 255, as OpenImageIO gives them for 8-bit files (no sRGB decoding).
        const Image im = read_ppm(path);
        FloatImage f;
        f.width = im.width;
        f.height = im.height;
        f.rgb.resize(std::size_t{3} * im.width * im.height);
        for (std::size_t i = 0; i < im.rgba8.size(); ++i)
            for (int c = 0; c < 3; ++c)
                f.rgb[3 * i + c] = static_cast<float>((im.rgba8[i] >> (8 * c)) & 0xffu) / 255.0f;
        return f;
    }
    if (!have_oiio()) {
        throw Error(path.string() + ": this build has no OpenImageIO, so it reads only .pfm and .ppm images");
    }
    return detail::read_oiio(path);
}

#ifndef PRT_HAVE_OIIO
namespace detail {
bool oiio_can_write(const std::filesystem::path&) {
    return false;
}
void write_oiio(const std::filesystem::path& path, const Image&, float) {
    throw Error(path.string() + ": this build has no OpenImageIO");
}
FloatImage read_oiio(const std::filesystem::path& path) {
    throw Error(path.string() + ": this build has no OpenImageIO");
}
}  // namespace detail
#endif

}  // namespace prt::rt
