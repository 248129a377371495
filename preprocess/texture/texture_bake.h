// PointRT preprocess: tri-planar colors for every point of a pool (thesis 5.5), over all cores.
// Image files are read elsewhere (prt_texture.cpp through prt::rt::read_float_image); this library
// needs no image library.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "prt/formats/pool_layout.h"
#include "triplanar.h"

namespace prt::pre::texture {

/// How the texture combines with colors the pool already has.
enum class Blend {
    replace,   ///< the texture's color
    multiply,  ///< old color x texture, in linear RGB (white where the pool has no colors)
};

/// Tri-planar colors (eq. 5.5) of points given in a model's local frame (`positions` relative to
/// `local_origin`, which is ModelInfo::origin; the projection's origin `params.origin` is in the
/// same model frame). `old_colors` is empty or one per point. Returns sRGB-encoded RGBA8, alpha
/// taken from the old color (255 without). Throws prt::Error when sizes disagree or a texture is
/// empty or the scale is not positive.
std::vector<pool::Rgba8> bake_triplanar(std::span<const pool::Float3> positions,
                                        std::span<const pool::Float3> normals,
                                        std::span<const pool::Rgba8> old_colors, const D3& local_origin,
                                        const TextureView (&textures)[3], const TriplanarParams& params,
                                        Blend blend, unsigned threads = 0);

}  // namespace prt::pre::texture
