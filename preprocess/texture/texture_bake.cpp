#include "texture_bake.h"

#include <string>

#include "prt/error.h"
#include "prt/parallel.h"

namespace prt::pre::texture {

std::vector<pool::Rgba8> bake_triplanar(std::span<const pool::Float3> positions,
                                        std::span<const pool::Float3> normals,
                                        std::span<const pool::Rgba8> old_colors, const D3& local_origin,
                                        const TextureView (&textures)[3], const TriplanarParams& params,
                                        Blend blend, unsigned threads) {
    if (normals.size() != positions.size())
        throw Error("tri-planar texture: " + std::to_string(normals.size()) + " normals for " +
                    std::to_string(positions.size()) + " points");
    if (!old_colors.empty() && old_colors.size() != positions.size())
        throw Error("tri-planar texture: " + std::to_string(old_colors.size()) + " colors for " +
                    std::to_string(positions.size()) + " points");
    if (!(params.scale > 0.0) || !std::isfinite(params.scale))
        throw Error("tri-planar texture: the scale must be a positive number");
    if (!(params.sharpness >= 0.0) || !std::isfinite(params.sharpness))
        throw Error("tri-planar texture: the sharpness must be a non-negative number");
    for (const TextureView& t : textures)
        if (t.rgb == nullptr || t.width == 0 || t.height == 0) throw Error("tri-planar texture: empty image");

    std::vector<pool::Rgba8> out(positions.size());
    parallel_chunks(positions.size(), 1u << 14, resolve_threads(threads),
                    [&](std::size_t begin, std::size_t end, unsigned) {
                        for (std::size_t i = begin; i < end; ++i) {
                            const pool::Float3& q = positions[i];
                            // The model frame in double: local offsets plus the pool's origin.
                            const D3 p{local_origin[0] + q.x, local_origin[1] + q.y, local_origin[2] + q.z};
                            const D3 n{normals[i].x, normals[i].y, normals[i].z};
                            D3 c = triplanar_color(textures, p, n, params);
                            std::uint8_t alpha = 255;
                            if (!old_colors.empty()) {
                                const pool::Rgba8& o = old_colors[i];
                                alpha = o.a;
                                if (blend == Blend::multiply) {
                                    c[0] *= srgb8_to_linear(o.r);
                                    c[1] *= srgb8_to_linear(o.g);
                                    c[2] *= srgb8_to_linear(o.b);
                                }
                            }
                            out[i] = pool::Rgba8{linear_to_srgb8(c[0]), linear_to_srgb8(c[1]),
                                                 linear_to_srgb8(c[2]), alpha};
                        }
                    });
    return out;
}

}  // namespace prt::pre::texture
