// PointRT scene description: the values of a scene file (SCENE.md) that kernels read as they are.
// Plain types only: this header compiles under g++ and nvcc, like the pool's *_layout.h headers.
// The scene parser (prt/formats/scene.h), the runtime's loader and the core's ModelView
// (prt/core/scene_view.h) share this one SurfaceKind, and its names are parsed and written here
// only.
#pragma once

#include <cstdint>
#include <string_view>

namespace prt::scene {

/// Which representation of a model rays meet (SCENE.md models[].surface, DESIGN.md "surfaces").
/// The values index k_surface_names and are the bits of the core's KernelMask (render.h).
enum class SurfaceKind : std::uint32_t {
    splats = 0,   ///< thesis 3: splats in the octree (sections 16-19)
    iso = 1,      ///< thesis 4: the Implicit Surface Octree (sections 32-35)
    mls = 2,      ///< WS05: the exact MLS surface over the kd-tree and its BVH (sections 48-53)
    patches = 3,  ///< seed 002: bicubic Bezier patches (sections 112-115)
};

/// How many surface kinds there are.
inline constexpr std::uint32_t k_surface_kind_count = 4;

/// The scene file's name of each kind, indexed by its value.
inline constexpr std::string_view k_surface_names[k_surface_kind_count] = {"splats", "iso", "mls", "patches"};

/// The scene file's name of a kind ("splats", "iso", "mls", "patches").
constexpr std::string_view surface_name(SurfaceKind kind) {
    const auto i = static_cast<std::uint32_t>(kind);
    return i < k_surface_kind_count ? k_surface_names[i] : std::string_view{"splats"};
}

/// Parses a surface name; false (and `out` unchanged) for anything else.
constexpr bool parse_surface(std::string_view text, SurfaceKind& out) {
    for (std::uint32_t i = 0; i < k_surface_kind_count; ++i) {
        if (text == k_surface_names[i]) {
            out = static_cast<SurfaceKind>(i);
            return true;
        }
    }
    return false;
}

/// "splats, iso, mls or patches": the names for messages.
inline constexpr std::string_view k_surface_name_list = "splats, iso, mls or patches";

namespace detail {
/// Whether k_surface_name_list lists k_surface_names in order, joined by ", " and " or ".
constexpr bool surface_name_list_matches() {
    std::string_view rest = k_surface_name_list;
    for (std::uint32_t i = 0; i < k_surface_kind_count; ++i) {
        const std::string_view sep = i == 0 ? "" : i + 1 == k_surface_kind_count ? " or " : ", ";
        if (rest.substr(0, sep.size()) != sep) return false;
        rest.remove_prefix(sep.size());
        if (rest.substr(0, k_surface_names[i].size()) != k_surface_names[i]) return false;
        rest.remove_prefix(k_surface_names[i].size());
    }
    return rest.empty();
}
}  // namespace detail
static_assert(detail::surface_name_list_matches(), "k_surface_name_list must name every surface kind");

}  // namespace prt::scene
