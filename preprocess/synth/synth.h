// PointRT synthetic models: point sets sampled from the analytic shapes of analytic.h, uniformly by
// area, with exact normals, optional noise along the normal and per-part colors. prt-synth is a thin
// command line over synthesize(); tests call it directly.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "analytic.h"
#include "point_cloud.h"

namespace prt::synth {

/// How the (u, v) parameters of each surface patch are drawn.
enum class Sampling : std::uint32_t {
    /// Roberts' R2 low-discrepancy sequence (generalised golden ratio, plastic number), shifted per
    /// patch by the seed (Cranley-Patterson rotation): blue-noise-like spacing for any N.
    r2,
    /// Independent uniform random (u, v) per point (a counter-based hash of seed, patch, index).
    random,
};
const char* sampling_name(Sampling s);

enum class ColorMode : std::uint32_t {
    none,      ///< no color section
    parts,     ///< each part its color: room parts, cube faces; one color for single-part shapes
    normal,    ///< the normal mapped to RGB: (n + 1) / 2 * 255
    constant,  ///< SynthOptions::color everywhere
};
const char* color_mode_name(ColorMode m);
/// The color ColorMode::normal gives the unit normal n: (n + 1) / 2 * 255 per channel.
pool::Rgba8 normal_color(const Vec3& n);

struct SynthOptions {
    Shape shape;
    std::uint64_t count = 100000;  ///< points to generate (exactly this many)
    Sampling sampling = Sampling::r2;
    /// Standard deviation of the Gaussian displacement along the normal, relative to
    /// shape_size(shape); 0 = points exactly on the surface. Truncated at k_noise_truncation sigma.
    double noise = 0.0;
    std::uint64_t seed = 1;
    ColorMode colors = ColorMode::none;
    pool::Rgba8 color{200, 200, 200, 255};  ///< for ColorMode::constant and single-part shapes
    unsigned threads = 0;                   ///< 0 = every available core (prt::available_cores)
};

/// Noise draws beyond this many standard deviations are redrawn, so |displacement| is bounded.
inline constexpr double k_noise_truncation = 4.0;
/// Splat::point is 32-bit: a pool holds at most this many points.
inline constexpr std::uint64_t k_max_points = 0xFFFFFFFFull;

/// A contiguous range of generated points that belong to one part.
struct PartRange {
    std::string name;
    std::uint64_t first = 0;
    std::uint64_t count = 0;
    double area = 0;      ///< world units
    pool::Rgba8 color{};  ///< its color under ColorMode::parts
};

struct SynthResult {
    pre::PointCloud cloud;         ///< world frame, normals unit, flags has k_model_synthetic
    std::vector<PartRange> parts;  ///< in point order, covering [0, count)
    double noise_sigma = 0.0;      ///< absolute standard deviation, world units
    /// Provenance parameters: {"shape": shape_to_json, "points", "sampling", "seed", "noise",
    /// "noise_sigma", "noise_truncation", "colors", "parts": [{name, first, count, area, color}]}.
    std::string parameters_json;
};

/// Throws prt::Error naming the first invalid option (shape parameters, count, noise, threads).
void validate(const SynthOptions& options);

/// Generates the point set. Points are allocated to patches (faces, the sphere, the torus)
/// proportionally to area by largest remainders, so per-part counts are exact to one point; each
/// point depends only on (seed, patch, index), so the output is identical for any thread count.
/// `progress(done, total)` is called from the calling thread only. Throws prt::Error on invalid
/// options.
SynthResult synthesize(const SynthOptions& options,
                       const std::function<void(std::uint64_t, std::uint64_t)>& progress = {});

}  // namespace prt::synth
