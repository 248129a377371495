// PointRT pool file: the on-disk (and in-memory) layout. Plain structs only: this header compiles
// under both g++ and nvcc and is what the runtime core reads section payloads through.
//
//   byte 0                                                              (all little-endian)
//   +----------------------------+
//   | PoolHeader        64 bytes |  magic "PRTPOOL\0", format version, file size, section table
//   +----------------------------+
//   | SectionEntry[n]  64 bytes each, at header.table_offset (= 64)
//   +----------------------------+
//   | padding to 256             |
//   +----------------------------+
//   | section 0 payload          |  every payload starts on a 256-byte boundary, so a mapped
//   | padding to 256             |  section can be handed to cudaMemcpy or reinterpret_cast
//   | section 1 payload          |  without conversion
//   | ...                        |
//   +----------------------------+  header.file_size
//
// Checksums are XXH3-64 (xxHash): one over the header (bytes 0..55), one over the section table,
// one per payload. Readers reject a newer major format version and a newer section version.
// The full specification, with the rules readers enforce, is formats/POOL.md.
#pragma once

#include <cstddef>
#include <cstdint>

namespace prt::pool {

inline constexpr char k_magic[8] = {'P', 'R', 'T', 'P', 'O', 'O', 'L', '\0'};
inline constexpr std::uint32_t k_format_major = 1;  ///< bumped on any incompatible change
inline constexpr std::uint32_t k_format_minor = 0;  ///< bumped when section types are added
inline constexpr std::uint64_t k_alignment = 256;   ///< payload alignment in bytes
/// Readers refuse tables longer than this before allocating anything (resource limit).
inline constexpr std::uint32_t k_max_sections = 4096;

/// Section types. Ranges are reserved per pipeline step so a newcomer can find the owner:
///   1-15 points (prt-import, prt-synth, prt-radii), 16-31 splat octree (prt-octree, prt-cull),
///   32-47 ISO (prt-iso), 48-63 MLS kd-tree (prt-mls), 64-79 caustics (prt-photons),
///   80-95 light map (prt-lightmap), 96-111 textures (prt-texture), 112-127 patches (prt-patches),
///   128-143 bricks and level of detail (prt-bricks).
enum class SectionType : std::uint32_t {
    provenance = 1,     ///< UTF-8 JSON array of {tool, version, parameters, time}; element = 1 byte
    model_info = 2,     ///< one ModelInfo
    positions = 3,      ///< Float3 per point, relative to ModelInfo::origin
    normals = 4,        ///< Float3 per point, unit length
    colors = 5,         ///< Rgba8 per point
    radii = 6,          ///< float per point: splat radius (prt-radii, thesis 3.1)
    material_ids = 7,   ///< uint32 per point: index into the scene's material list
    intensities = 8,    ///< float per point: the scanner's return intensity, as read (PLY/PCD intensity)
    sensors = 9,        ///< Sensor per scan: where its scanner stood (or the direction to it), world frame
    scan_ids = 10,      ///< uint16 per point: index into sensors of the scan that measured the point
    octree_info = 16,   ///< one OctreeInfo (prt-octree, thesis 2.2 / 3.2)
    octree_nodes = 17,  ///< uint32 per node: 2-bit type + 30-bit address (OctreeNode helpers)
    leaf_info = 18,     ///< uint32 per filled leaf + 1: begin index into splats (thesis 3.2)
    splats = 19,        ///< Splat per stored splat, leaf-contiguous, replicas included
    // 32-47: ISO (prt-iso, thesis ch. 4); layouts in iso_layout.h
    iso_info = 32,        ///< one IsoInfo
    iso_nodes = 33,       ///< uint32 node words (octree_nodes encoding), filled leaf -> leaf index
    iso_leaves_q8 = 34,   ///< IsoLeafQ8 per filled leaf (56 B, thesis 4.4)
    iso_leaves_f32 = 35,  ///< IsoLeafF32 per filled leaf (160 B)
    // 48-63: exact MLS kd-tree (prt-mls, Wald-Seidel 2005); layouts in mls_layout.h
    mls_info = 48,        ///< one MlsInfo
    mls_nodes = 49,       ///< MlsNode per kd-tree node
    mls_refs = 50,        ///< uint32 splat indices referenced by the kd-tree leaves
    mls_splats = 51,      ///< MlsSplat per unique splat
    mls_bvh_nodes = 52,   ///< MlsBvhNode per BVH node over the non-empty kd leaves (optional)
    mls_bvh_leaves = 53,  ///< MlsBvhLeaf per non-empty kd leaf (with mls_bvh_nodes)
    // 64-79: caustic octree (prt-photons, thesis 5.4); 80-95: light map (prt-lightmap, thesis 5.3);
    // layouts in gi_layout.h
    caustic_info = 64,      ///< one GiInfo
    caustic_nodes = 65,     ///< uint32 node words (octree_nodes encoding), filled leaf -> leaf index
    caustic_leaves = 66,    ///< GiLeaf per filled leaf: corner irradiance (eq. 5.1-5.2)
    light_map_info = 80,    ///< one GiInfo
    light_map_nodes = 81,   ///< uint32 node words
    light_map_leaves = 82,  ///< GiLeaf per filled leaf: corner indirect irradiance (eq. 5.3-5.4)
    // 112-127: Bezier patches (prt-patches, seed 002); layouts in patch_layout.h
    patch_info = 112,            ///< one PatchInfo
    patch_control_points = 113,  ///< 16 control points per patch
    patch_bvh = 114,             ///< BVH nodes over patch bounding boxes, depth first with skips
    patch_subpatch_boxes = 115,  ///< fixed-depth subpatch tree boxes per patch
    // 128-143: bricks and level of detail (prt-bricks, issue 17); layouts in brick_layout.h
    brick_info = 128,       ///< one BrickInfo
    brick_top_nodes = 129,  ///< uint32 node words of the resident top tree; NodeType::brick -> brick
    brick_table = 130,      ///< BrickEntry per brick: cube, payload range, counts, checksum
    brick_data = 131,       ///< bytes: each brick's header, nodes, leaf_info, compressed splats
    lod_splats = 132,       ///< LodSplat per top node: the representative disc of its subtree
    brick_lod = 133,        ///< BrickLod per brick: its level-of-detail prefix's decode cube and range
    lod_nodes = 134,        ///< uint32 node words of every brick's LOD prefix
    lod_discs = 135,        ///< CompressedSplat per lod_nodes word: the disc of the node's subtree
};

// Name, version, element size and writer of each type: the section table (section_table.h).

struct Float3 {
    float x, y, z;  // 0, 4, 8
};
static_assert(sizeof(Float3) == 12);

struct Rgba8 {
    std::uint8_t r, g, b, a;  // 0, 1, 2, 3
};
static_assert(sizeof(Rgba8) == 4);

/// The fixed file header (64 bytes at offset 0).
struct PoolHeader {
    char magic[8];                  ///< 0: k_magic
    std::uint32_t format_major;     ///< 8
    std::uint32_t format_minor;     ///< 12
    std::uint64_t file_size;        ///< 16: total bytes, checked against the real size
    std::uint32_t section_count;    ///< 24: entries in the section table
    std::uint32_t flags;            ///< 28: reserved, 0
    std::uint64_t table_offset;     ///< 32: byte offset of SectionEntry[section_count]
    std::uint64_t table_checksum;   ///< 40: XXH3-64 of the section table
    std::uint64_t reserved;         ///< 48: 0
    std::uint64_t header_checksum;  ///< 56: XXH3-64 of bytes 0..55
};
static_assert(sizeof(PoolHeader) == 64);
static_assert(offsetof(PoolHeader, header_checksum) == 56);

/// One entry of the section table (64 bytes).
struct SectionEntry {
    std::uint32_t type;          ///< 0: SectionType
    std::uint32_t version;       ///< 4: section_version(type) when written
    std::uint64_t offset;        ///< 8: payload byte offset, multiple of k_alignment
    std::uint64_t size;          ///< 16: payload bytes = count * element_size
    std::uint64_t count;         ///< 24: number of elements
    std::uint32_t element_size;  ///< 32: bytes per element
    std::uint32_t flags;         ///< 36: reserved, 0
    std::uint64_t checksum;      ///< 40: XXH3-64 of the payload
    char name[16];               ///< 48: section_name(type), NUL-padded (informative)
};
static_assert(sizeof(SectionEntry) == 64);
static_assert(offsetof(SectionEntry, checksum) == 40);

/// Model-wide facts (section model_info, exactly one element). Positions are stored as float
/// offsets from `origin` (double), so a scan 1e6 units from the world origin keeps full float
/// precision relative to its own size (DESIGN.md, numerical robustness).
struct ModelInfo {
    double origin[3];           ///< 0: world position of the local frame's origin
    float bounds_min[3];        ///< 24: bounding box of the points, local frame
    float bounds_max[3];        ///< 36
    std::uint64_t point_count;  ///< 48: elements in every per-point section
    std::uint32_t flags;        ///< 56: ModelFlags
    std::uint32_t reserved;     ///< 60: 0
};
static_assert(sizeof(ModelInfo) == 64);
static_assert(offsetof(ModelInfo, point_count) == 48);

/// One scan's sensor (section sensors; real scans, issue 15). Normals estimated at import are
/// oriented toward the sensor of the scan each point came from (section scan_ids; a pool with one
/// sensor and no scan_ids: every point's). World frame, double, like ModelInfo::origin.
struct Sensor {
    double position[3];      ///< 0: k_sensor_point: the scanner's position; k_sensor_direction: the
                             ///<    unit direction from the scene toward a sensor at infinity
    std::uint32_t kind;      ///< 24: SensorKind
    std::uint32_t reserved;  ///< 28: 0
};
static_assert(sizeof(Sensor) == 32);
static_assert(offsetof(Sensor, kind) == 24);

enum SensorKind : std::uint32_t {
    k_sensor_point = 0,      ///< a scanner position (PCD VIEWPOINT, a PLY camera, a pose's origin)
    k_sensor_direction = 1,  ///< a far sensor: rays arrive from this direction (bun.conf's +z)
};
/// scan_ids are 16-bit: a pool holds at most this many sensors.
inline constexpr std::uint32_t k_max_sensors = 65536;

/// ModelInfo::flags bits.
enum ModelFlags : std::uint32_t {
    k_model_normals_estimated = 1u << 0,  ///< normals came from PCA, not from the source file
    k_model_synthetic = 1u << 1,          ///< made by prt-synth: the provenance names the shape
};

// ---- Splat octree (thesis 2.2, 3.2; written by prt-octree, thinned by prt-cull) ----------------
//
// Nodes are 32-bit words: bits 31..30 the type, bits 29..0 the address.
//   internal     -> address = index of the first of its 8 children in octree_nodes; the 8 children
//                   are stored together in Morton (space-filling-curve) order, child index
//                   c = x | (y << 1) | (z << 2) where x,y,z in {0,1} pick the upper half per axis
//   filled leaf  -> address = index into leaf_info; its splats are splats[leaf_info[a], leaf_info[a+1])
//   empty leaf   -> address = 0
//   brick        -> address = index into brick_table (only in brick_top_nodes, brick_layout.h)
// Node 0 is the root; nodes are stored breadth first (level by level).

enum class NodeType : std::uint32_t { internal = 0, filled_leaf = 1, empty_leaf = 2, brick = 3 };
inline constexpr std::uint32_t k_node_address_bits = 30;
inline constexpr std::uint32_t k_node_address_max = (1u << k_node_address_bits) - 1;

inline constexpr std::uint32_t make_node(NodeType type, std::uint32_t address) {
    return (static_cast<std::uint32_t>(type) << k_node_address_bits) | (address & k_node_address_max);
}
inline constexpr NodeType node_type(std::uint32_t node) {
    return static_cast<NodeType>(node >> k_node_address_bits);
}
inline constexpr std::uint32_t node_address(std::uint32_t node) {
    return node & k_node_address_max;
}

/// Octree-wide facts (section octree_info, exactly one element). The root is a cube in the
/// model's local frame (ModelInfo::origin), so traversal can run in normalized [0,1]^3 coordinates.
struct OctreeInfo {
    float root_min[3];              ///< 0: root cube corner, local frame
    float root_size;                ///< 12: root cube edge length
    std::uint32_t depth;            ///< 16: deepest level (root = level 0)
    std::uint32_t max_leaf_splats;  ///< 20: the X of thesis 3.2 used when building
    std::uint32_t node_count;       ///< 24: elements of octree_nodes
    std::uint32_t filled_leaves;    ///< 28: elements of leaf_info minus one
    std::uint64_t splat_count;      ///< 32: elements of splats (replicas included)
    std::uint64_t unique_splats;    ///< 40: splats before replication (= points with a radius)
    std::uint32_t flags;            ///< 48: OctreeFlags
    std::uint32_t reserved[3];      ///< 52: 0
};
static_assert(sizeof(OctreeInfo) == 64);
static_assert(offsetof(OctreeInfo, splat_count) == 32);

enum OctreeFlags : std::uint32_t {
    k_octree_replicated = 1u << 0,  ///< splats are replicated into every leaf their disk overlaps
    k_octree_culled = 1u << 1,      ///< prt-cull removed replicas no probe ray needed (thesis 3.4)
};

/// One stored splat (32 bytes, thesis 3.2: 8 floats): an oriented disk.
struct Splat {
    Float3 position;      ///< 0: centre, local frame
    float radius;         ///< 12
    Float3 normal;        ///< 16: unit
    std::uint32_t point;  ///< 28: index of the source point (colors, material_ids)
};
static_assert(sizeof(Splat) == 32);
static_assert(offsetof(Splat, point) == 28);

}  // namespace prt::pool
