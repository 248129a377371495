// The only file of the runtime that includes OpenImageIO (built when PRT_HAVE_PRT_WITH_OIIO).
#include <OpenImageIO/imageio.h>

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <string>

#include "prt/atomic_file.h"
#include "prt/error.h"
#include "prt/runtime/image.h"

namespace prt::rt::detail {

bool oiio_can_write(const std::filesystem::path& path) {
    auto out = OIIO::ImageOutput::create(path.string());
    OIIO::geterror();  // clear the message of a failed lookup
    return out != nullptr;
}

void write_oiio(const std::filesystem::path& path, const Image& image, float exposure) {
    std::string ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    const bool is_float = ext == ".exr" || ext == ".hdr" || ext == ".pfm";
    AtomicFile file(path, /*keep_extension=*/true);  // removes the temporary file unless committed
    auto out = OIIO::ImageOutput::create(path.string());
    if (!out) throw Error(path.string() + ": no writer for this format (" + OIIO::geterror() + ")");
    OIIO::ImageSpec spec(static_cast<int>(image.width), static_cast<int>(image.height), 3,
                         is_float ? OIIO::TypeDesc::FLOAT : OIIO::TypeDesc::UINT8);
    if (!out->open(file.temporary(), spec)) throw Error(path.string() + ": cannot write (" + out->geterror() + ")");
    bool ok;
    const std::size_t n = static_cast<std::size_t>(image.width) * image.height;
    if (is_float) {
        std::vector<float> px(n * 3);
        for (std::size_t i = 0; i < n * 3; ++i) px[i] = image.rgb[i] * exposure;
        ok = out->write_image(OIIO::TypeDesc::FLOAT, px.data());
    } else {
        std::vector<unsigned char> px(n * 3);
        for (std::size_t i = 0; i < n; ++i) {
            const std::uint32_t p = image.rgba8[i];
            px[i * 3] = p & 0xff;
            px[i * 3 + 1] = (p >> 8) & 0xff;
            px[i * 3 + 2] = (p >> 16) & 0xff;
        }
        ok = out->write_image(OIIO::TypeDesc::UINT8, px.data());
    }
    const std::string err = ok ? std::string() : out->geterror();
    out->close();
    if (!ok) throw Error(path.string() + ": write failed (" + err + ")");
    file.commit();
}

namespace {
/// OpenImageIO's messages may span several lines (and repeat the file name); errors here are one line.
std::string one_line(std::string message) {
    for (char& c : message)
        if (c == '\n' || c == '\r') c = ' ';
    while (!message.empty() && message.back() == ' ') message.pop_back();
    return message.empty() ? std::string("unknown reason") : message;
}

/// Silences file descriptor 2 while alive: libpng (under OpenImageIO 2.4) prints "libpng error:
/// ..." to stderr itself before OpenImageIO reports the same problem, which would break the
/// one-line error rule. Reading images happens while loading, not while rendering, so the short
/// window in which other threads' stderr output is lost costs nothing.
class QuietStderr {
public:
    QuietStderr() {
        std::fflush(stderr);
        m_saved = ::dup(2);
        const int null_fd = ::open("/dev/null", O_WRONLY);
        if (m_saved >= 0 && null_fd >= 0) ::dup2(null_fd, 2);
        if (null_fd >= 0) ::close(null_fd);
    }
    ~QuietStderr() {
        std::fflush(stderr);
        if (m_saved >= 0) {
            ::dup2(m_saved, 2);
            ::close(m_saved);
        }
    }
    QuietStderr(const QuietStderr&) = delete;
    QuietStderr& operator=(const QuietStderr&) = delete;

private:
    int m_saved = -1;
};
}  // namespace

FloatImage read_oiio(const std::filesystem::path& path) {
    QuietStderr quiet;
    auto in = OIIO::ImageInput::open(path.string());
    if (!in) throw Error(path.string() + ": cannot read image (" + one_line(OIIO::geterror()) + ")");
    const OIIO::ImageSpec& spec = in->spec();
    if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0)
        throw Error(path.string() + ": empty image");
    const int channels = spec.nchannels;
    std::vector<float> px(static_cast<std::size_t>(spec.width) * spec.height * channels);
    if (!in->read_image(0, 0, 0, channels, OIIO::TypeDesc::FLOAT, px.data())) {
        throw Error(path.string() + ": cannot read pixels (" + one_line(in->geterror()) + ")");
    }
    // 8-bit images are display-encoded (sRGB); float images are linear already.
    const bool srgb =
        spec.format.basetype == OIIO::TypeDesc::UINT8 || spec.format.basetype == OIIO::TypeDesc::UINT16;
    FloatImage img;
    img.width = static_cast<std::uint32_t>(spec.width);
    img.height = static_cast<std::uint32_t>(spec.height);
    img.rgb.resize(static_cast<std::size_t>(img.width) * img.height * 3);
    for (std::size_t i = 0; i < static_cast<std::size_t>(img.width) * img.height; ++i) {
        for (int c = 0; c < 3; ++c) {
            // Grey (1 channel) and grey + alpha (2 channels) replicate the grey channel; RGB(A) takes
            // the first three (a 2-channel image used to take its alpha as green).
            float v = px[i * channels + (channels >= 3 ? c : 0)];
            if (srgb) v = v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
            img.rgb[i * 3 + c] = std::isfinite(v) ? v : 0.0f;
        }
    }
    return img;
}

}  // namespace prt::rt::detail
