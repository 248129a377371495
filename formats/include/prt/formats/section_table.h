// PointRT pool file: the one table of section types (formats/POOL.md, "Section types"). A row per
// SectionType: its name, the payload layout version this build reads and writes, the element size,
// whether it holds one element per point, and the tools that write it. section_name,
// section_version, section_element_size and section_per_point are looked up here, so adding a
// section type is one row (plus its layout struct); PoolFile::open checks every known type's
// version and element size against it. Plain constexpr: compiles under g++ and nvcc.
#pragma once

#include <cstddef>
#include <cstdint>
#include <iterator>

#include "prt/formats/brick_layout.h"
#include "prt/formats/gi_layout.h"
#include "prt/formats/iso_layout.h"
#include "prt/formats/mls_layout.h"
#include "prt/formats/patch_layout.h"
#include "prt/formats/pool_layout.h"

namespace prt::pool {

/// One row of the section table.
struct SectionTypeInfo {
    SectionType type;
    const char* name;            ///< SectionEntry::name and every error message ("section NAME: ...")
    std::uint32_t version;       ///< current layout version of the payload; bump on any change
    std::uint32_t element_size;  ///< bytes per element; readers refuse another size
    bool per_point;              ///< holds ModelInfo::point_count elements, one per point
    const char* written_by;      ///< the tools that write it
};

// clang-format off
inline constexpr SectionTypeInfo k_section_types[] = {
    // 1-15: points
    {SectionType::provenance,   "provenance",   1, 1,                     false, "every tool"},
    {SectionType::model_info,   "model_info",   1, sizeof(ModelInfo),     false, "prt-import, prt-synth, prt-patches"},
    {SectionType::positions,    "positions",    1, sizeof(Float3),        true,  "prt-import, prt-synth"},
    {SectionType::normals,      "normals",      1, sizeof(Float3),        true,  "prt-import, prt-synth"},
    {SectionType::colors,       "colors",       1, sizeof(Rgba8),         true,  "prt-import, prt-synth, prt-texture"},
    {SectionType::radii,        "radii",        1, sizeof(float),         true,  "prt-radii"},
    {SectionType::material_ids, "material_ids", 1, sizeof(std::uint32_t), true,  "(scene tools)"},
    {SectionType::intensities,  "intensities",  1, sizeof(float),         true,  "prt-import"},
    {SectionType::sensors,      "sensors",      1, sizeof(Sensor),        false, "prt-import, prt-synth"},
    {SectionType::scan_ids,     "scan_ids",     1, sizeof(std::uint16_t), true,  "prt-import, prt-synth"},
    // 16-31: splat octree
    {SectionType::octree_info,  "octree_info",  1, sizeof(OctreeInfo),    false, "prt-octree, prt-cull"},
    {SectionType::octree_nodes, "octree_nodes", 1, sizeof(std::uint32_t), false, "prt-octree"},
    {SectionType::leaf_info,    "leaf_info",    1, sizeof(std::uint32_t), false, "prt-octree, prt-cull"},
    {SectionType::splats,       "splats",       1, sizeof(Splat),         false, "prt-octree, prt-cull"},
    // 32-47: Implicit Surface Octree
    {SectionType::iso_info,       "iso_info",       1, sizeof(IsoInfo),       false, "prt-iso"},
    {SectionType::iso_nodes,      "iso_nodes",      1, sizeof(std::uint32_t), false, "prt-iso"},
    {SectionType::iso_leaves_q8,  "iso_leaves_q8",  1, sizeof(IsoLeafQ8),     false, "prt-iso"},
    {SectionType::iso_leaves_f32, "iso_leaves_f32", 1, sizeof(IsoLeafF32),    false, "prt-iso"},
    // 48-63: MLS kd-tree
    {SectionType::mls_info,   "mls_info",   1, sizeof(MlsInfo),       false, "prt-mls"},
    {SectionType::mls_nodes,  "mls_nodes",  1, sizeof(MlsNode),       false, "prt-mls"},
    {SectionType::mls_refs,   "mls_refs",   1, sizeof(std::uint32_t), false, "prt-mls"},
    {SectionType::mls_splats, "mls_splats", 1, sizeof(MlsSplat),      false, "prt-mls"},
    {SectionType::mls_bvh_nodes,  "mls_bvh_nodes",  1, sizeof(MlsBvhNode), false, "prt-mls"},
    {SectionType::mls_bvh_leaves, "mls_bvh_leaves", 1, sizeof(MlsBvhLeaf), false, "prt-mls"},
    // 64-79: caustic octree; 80-95: light map
    {SectionType::caustic_info,     "caustic_info",     1, sizeof(GiInfo),        false, "prt-photons"},
    {SectionType::caustic_nodes,    "caustic_nodes",    1, sizeof(std::uint32_t), false, "prt-photons"},
    {SectionType::caustic_leaves,   "caustic_leaves",   1, sizeof(GiLeaf),        false, "prt-photons"},
    {SectionType::light_map_info,   "light_map_info",   1, sizeof(GiInfo),        false, "prt-lightmap"},
    {SectionType::light_map_nodes,  "light_map_nodes",  1, sizeof(std::uint32_t), false, "prt-lightmap"},
    {SectionType::light_map_leaves, "light_map_leaves", 1, sizeof(GiLeaf),        false, "prt-lightmap"},
    // 112-127: Bezier patches
    {SectionType::patch_info,           "patch_info",           1, sizeof(PatchInfo),       false, "prt-patches"},
    {SectionType::patch_control_points, "patch_control_points", 1, sizeof(PatchControlNet), false, "prt-patches"},
    {SectionType::patch_bvh,            "patch_bvh",            1, sizeof(PatchBvhNode),    false, "prt-patches"},
    {SectionType::patch_subpatch_boxes, "patch_subpatch_boxes", 1, sizeof(SubpatchNode),    false, "prt-patches"},
    // 128-143: bricks and level of detail
    {SectionType::brick_info,      "brick_info",      1, sizeof(BrickInfo),     false, "prt-bricks"},
    {SectionType::brick_top_nodes, "brick_top_nodes", 1, sizeof(std::uint32_t), false, "prt-bricks"},
    {SectionType::brick_table,     "brick_table",     1, sizeof(BrickEntry),    false, "prt-bricks"},
    {SectionType::brick_data,      "brick_data",      1, 1,                     false, "prt-bricks"},
    {SectionType::lod_splats,      "lod_splats",      1, sizeof(LodSplat),      false, "prt-bricks"},
    {SectionType::brick_lod,       "brick_lod",       1, sizeof(BrickLod),      false, "prt-bricks"},
    {SectionType::lod_nodes,       "lod_nodes",       1, sizeof(std::uint32_t), false, "prt-bricks"},
    {SectionType::lod_discs,       "lod_discs",       1, sizeof(CompressedSplat), false, "prt-bricks"},
};
// clang-format on

/// The table's row of a section type, or nullptr for a type this build does not know.
inline constexpr const SectionTypeInfo* section_type_info(SectionType type) {
    for (const SectionTypeInfo& row : k_section_types)
        if (row.type == type) return &row;
    return nullptr;
}

namespace detail {
/// A field of a section type's row, or `absent` for a type this build does not know.
template <class T>
inline constexpr T row_field(SectionType type, T SectionTypeInfo::*field, T absent) {
    const SectionTypeInfo* row = section_type_info(type);
    return row ? row->*field : absent;
}
}  // namespace detail

/// Current version of a section type's payload layout (0 for types this build does not know).
inline constexpr std::uint32_t section_version(SectionType type) {
    return detail::row_field(type, &SectionTypeInfo::version, 0u);
}

/// Human-readable name of a section type ("unknown" for types this build does not know).
inline constexpr const char* section_name(SectionType type) {
    return detail::row_field(type, &SectionTypeInfo::name, "unknown");
}

/// Element size a section type must have (0 for types this build does not know).
inline constexpr std::uint32_t section_element_size(SectionType type) {
    return detail::row_field(type, &SectionTypeInfo::element_size, 0u);
}

/// Whether a section type holds one element per point (ModelInfo::point_count).
inline constexpr bool section_per_point(SectionType type) {
    return detail::row_field(type, &SectionTypeInfo::per_point, false);
}

/// The tools that write a section type ("" for types this build does not know).
inline constexpr const char* section_writer(SectionType type) {
    return detail::row_field(type, &SectionTypeInfo::written_by, "");
}

namespace detail {
/// Rows in ascending type order (so each type once), versions and element sizes not 0.
inline constexpr bool section_table_well_formed() {
    // Indices, not pointers: GCC's UBSan instrumentation makes a pointer test non-constant.
    for (std::size_t i = 0; i < std::size(k_section_types); ++i) {
        if (i > 0 && !(k_section_types[i - 1].type < k_section_types[i].type)) return false;
        if (k_section_types[i].version == 0 || k_section_types[i].element_size == 0) return false;
    }
    return true;
}
}  // namespace detail
static_assert(detail::section_table_well_formed(),
              "k_section_types: ascending types, versions and sizes > 0");

}  // namespace prt::pool
