// prt-fuzz-seeds OUT_DIR: writes the binary part of the fuzz seed corpus into OUT_DIR/TARGET/
// (binary PLY in both byte orders, PCD binary and binary_compressed, pool files with every
// section type the reader validates) and a generated grid of Bezier patches (full-precision
// numbers, both patch formats). The text seeds live in tests/fuzz/corpus/TARGET/; binary and
// larger files are generated here instead of being committed. Run by scripts/fuzz.sh.
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "prt/formats/pool.h"

#if PRT_FUZZ_SEEDS_PCL
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>
#endif

namespace {

namespace fs = std::filesystem;
namespace pool = prt::pool;

/// Appends the bytes of a value in the given byte order.
template <class T>
void put(std::string& out, T value, bool big_endian) {
    unsigned char b[sizeof(T)];
    std::memcpy(b, &value, sizeof(T));
    if (big_endian == (std::endian::native == std::endian::little))
        for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
    out.append(reinterpret_cast<const char*>(b), sizeof(T));
}

void save(const fs::path& path, const std::string& bytes) {
    fs::create_directories(path.parent_path());
    std::ofstream out(path, std::ios::binary);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    if (!out) throw std::runtime_error("cannot write " + path.string());
}

// The four corners of a tetrahedron: every seed describes the same small solid.
constexpr float k_corners[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
constexpr std::uint32_t k_faces[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};

/// Binary PLY point set: float xyz, normals, uchar colors with alpha, radius, plus a face element.
std::string ply_points(bool big_endian) {
    std::string s = std::string("ply\nformat ") +
                    (big_endian ? "binary_big_endian" : "binary_little_endian") +
                    " 1.0\ncomment prt-fuzz seed\nelement vertex 4\nproperty float x\nproperty float y\n"
                    "property float z\nproperty float nx\nproperty float ny\nproperty float nz\n"
                    "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n"
                    "property float radius\nelement face 4\nproperty list uchar int vertex_indices\n"
                    "end_header\n";
    for (int i = 0; i < 4; ++i) {
        for (int a = 0; a < 3; ++a) put<float>(s, k_corners[i][a], big_endian);
        for (int a = 0; a < 3; ++a) put<float>(s, a == i % 3 ? 1.f : 0.f, big_endian);
        for (int a = 0; a < 4; ++a) put<std::uint8_t>(s, static_cast<std::uint8_t>(60 * i + a), big_endian);
        put<float>(s, 0.25f, big_endian);
    }
    for (const auto& f : k_faces) {
        put<std::uint8_t>(s, 3, big_endian);
        for (std::uint32_t v : f) put<std::int32_t>(s, static_cast<std::int32_t>(v), big_endian);
    }
    return s;
}

/// Binary PLY whose vertex rows have a list property (variable row size) and double coordinates,
/// 16-bit colors and an extra element after the faces.
std::string ply_variable_rows() {
    std::string s =
        "ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty double x\nproperty double y\n"
        "property double z\nproperty list uchar float extra\nproperty ushort red\nproperty ushort green\n"
        "property ushort blue\nelement range_grid 2\nproperty list uint int vertex_indices\nend_header\n";
    for (int i = 0; i < 4; ++i) {
        for (int a = 0; a < 3; ++a) put<double>(s, k_corners[i][a], false);
        put<std::uint8_t>(s, static_cast<std::uint8_t>(i), false);
        for (int k = 0; k < i; ++k) put<float>(s, 0.5f * k, false);
        for (int a = 0; a < 3; ++a) put<std::uint16_t>(s, static_cast<std::uint16_t>(20000 * a), false);
    }
    put<std::uint32_t>(s, 1, false);
    put<std::int32_t>(s, 2, false);
    put<std::uint32_t>(s, 0, false);
    return s;
}

/// Binary PLY mesh (tetrahedron) with per-vertex colors and no normals: the ply-mesh target.
std::string ply_mesh(bool big_endian) {
    std::string s = std::string("ply\nformat ") +
                    (big_endian ? "binary_big_endian" : "binary_little_endian") +
                    " 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
                    "property uchar red\nproperty uchar green\nproperty uchar blue\nelement face 4\n"
                    "property list uchar uint vertex_indices\nend_header\n";
    for (int i = 0; i < 4; ++i) {
        for (int a = 0; a < 3; ++a) put<float>(s, k_corners[i][a], big_endian);
        for (int a = 0; a < 3; ++a) put<std::uint8_t>(s, static_cast<std::uint8_t>(80 * a + i), big_endian);
    }
    for (const auto& f : k_faces) {
        put<std::uint8_t>(s, 3, big_endian);
        for (std::uint32_t v : f) put<std::uint32_t>(s, v, big_endian);
    }
    return s;
}

/// Binary PCD: x y z normal_x normal_y normal_z rgb (packed in a float) and a padding field.
std::string pcd_binary(std::uint32_t width, std::uint32_t height) {
    std::string s =
        "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\n"
        "FIELDS x y z normal_x normal_y normal_z rgb _\nSIZE 4 4 4 4 4 4 4 1\n"
        "TYPE F F F F F F F U\nCOUNT 1 1 1 1 1 1 1 4\nWIDTH " +
        std::to_string(width) + "\nHEIGHT " + std::to_string(height) + "\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " +
        std::to_string(width * height) + "\nDATA binary\n";
    for (std::uint32_t i = 0; i < width * height; ++i) {
        for (int a = 0; a < 3; ++a) put<float>(s, k_corners[i % 4][a], false);
        for (int a = 0; a < 3; ++a) put<float>(s, a == static_cast<int>(i % 3) ? 1.f : 0.f, false);
        put<std::uint32_t>(s, 0xFF000000u | (i * 0x102030u), false);
        s.append(4, '\0');
    }
    return s;
}

/// The pool sections every tool writes, plus an octree (root with 8 children, two filled leaves)
/// and a section of a type this build does not know (readers skip it after checking it).
std::vector<std::byte> pool_full(bool with_octree, bool with_unknown) {
    pool::PoolWriter w;
    pool::ModelInfo info{};
    info.origin[0] = 10.0;
    for (int a = 0; a < 3; ++a) {
        info.bounds_min[a] = -1.f;
        info.bounds_max[a] = 1.f;
    }
    info.point_count = 4;
    w.add_array(pool::SectionType::model_info, std::vector<pool::ModelInfo>{info});
    std::vector<pool::Float3> pos, nrm;
    std::vector<pool::Rgba8> col;
    std::vector<float> rad;
    for (int i = 0; i < 4; ++i) {
        pos.push_back({k_corners[i][0] - 0.5f, k_corners[i][1] - 0.5f, k_corners[i][2] - 0.5f});
        nrm.push_back({0.f, 0.f, 1.f});
        col.push_back({static_cast<std::uint8_t>(i), 2, 3, 255});
        rad.push_back(0.3f);
    }
    w.add_array(pool::SectionType::positions, pos);
    w.add_array(pool::SectionType::normals, nrm);
    w.add_array(pool::SectionType::colors, col);
    w.add_array(pool::SectionType::radii, rad);
    if (with_octree) {
        pool::OctreeInfo o{};
        for (int a = 0; a < 3; ++a) o.root_min[a] = -1.f;
        o.root_size = 2.f;
        o.depth = 1;
        o.max_leaf_splats = 16;
        o.node_count = 9;
        o.filled_leaves = 2;
        o.splat_count = 3;
        o.unique_splats = 3;
        o.flags = pool::k_octree_replicated;
        w.add_array(pool::SectionType::octree_info, std::vector<pool::OctreeInfo>{o});
        std::vector<std::uint32_t> nodes{pool::make_node(pool::NodeType::internal, 1)};
        for (int c = 0; c < 8; ++c)
            nodes.push_back(c == 0   ? pool::make_node(pool::NodeType::filled_leaf, 0)
                            : c == 7 ? pool::make_node(pool::NodeType::filled_leaf, 1)
                                     : pool::make_node(pool::NodeType::empty_leaf, 0));
        w.add_array(pool::SectionType::octree_nodes, nodes);
        w.add_array(pool::SectionType::leaf_info, std::vector<std::uint32_t>{0, 2, 3});
        std::vector<pool::Splat> splats;
        for (std::uint32_t i = 0; i < 3; ++i) splats.push_back({pos[i], 0.3f, nrm[i], i});
        w.add_array(pool::SectionType::splats, splats);
    }
    if (with_unknown) {
        const std::uint32_t words[4] = {1, 2, 3, 4};
        w.add(static_cast<pool::SectionType>(200), 4, 4,
              {reinterpret_cast<const std::byte*>(words), sizeof words});
    }
    w.add_provenance("prt-fuzz-seeds", "0", R"({"seed":true})");
    return w.serialize();
}

void save_pool(const fs::path& path, const std::vector<std::byte>& bytes) {
    save(path, std::string(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
}

}  // namespace

/// A 3 x 3 grid of bicubic patches over a wavy height field, neighbours sharing their edge
/// control points: .bpt (every patch with its 16 points) or Newell (shared vertices indexed once,
/// comma separated). Coordinates printed with 17 significant digits and exponents.
std::string patch_grid(bool newell) {
    constexpr int k_grid = 3;               // patches per side
    constexpr int k_side = 3 * k_grid + 1;  // control points per side
    const auto vertex = [](int i, int j) { return i * k_side + j; };
    std::vector<std::string> points;
    for (int i = 0; i < k_side; ++i)
        for (int j = 0; j < k_side; ++j) {
            char line[128];
            const double x = j / 3.0, y = i / 3.0, z = 0.25 * std::sin(x) * std::cos(1.7 * y) - 1e-7;
            std::snprintf(line, sizeof line, newell ? "%.17g,%.17g,%.17e\n" : "%.17g %.17g %.17e\n", x, y, z);
            points.emplace_back(line);
        }
    std::string s = std::to_string(k_grid * k_grid) + "\n";
    for (int pi = 0; pi < k_grid; ++pi)
        for (int pj = 0; pj < k_grid; ++pj) {
            if (!newell) s += "3 3\n";
            for (int k = 0; k < 16; ++k) {
                const int v = vertex(3 * pi + k / 4, 3 * pj + k % 4);
                if (newell)
                    s += std::to_string(v + 1) + (k == 15 ? "\n" : ",");
                else
                    s += points[v];
            }
        }
    if (newell) {
        s += std::to_string(points.size()) + "\n";
        for (const std::string& p : points) s += p;
    }
    return s;
}

int main(int argc, char** argv) {
    if (argc != 2) {
        std::fprintf(stderr,
                     "usage: prt-fuzz-seeds OUT_DIR\n  writes OUT_DIR/{ply,ply-mesh,pcd,pool,patches}/*\n");
        return 2;
    }
    const fs::path out = argv[1];
    try {
        save(out / "ply" / "points-le.ply", ply_points(false));
        save(out / "ply" / "points-be.ply", ply_points(true));
        save(out / "ply" / "variable-rows.ply", ply_variable_rows());
        save(out / "ply-mesh" / "tetra-le.ply", ply_mesh(false));
        save(out / "ply-mesh" / "tetra-be.ply", ply_mesh(true));
        save(out / "pcd" / "binary.pcd", pcd_binary(4, 1));
        save(out / "pcd" / "binary-organized.pcd", pcd_binary(2, 2));
#if PRT_FUZZ_SEEDS_PCL
        pcl::PointCloud<pcl::PointXYZRGBNormal> cloud;
        cloud.width = 2;
        cloud.height = 2;
        cloud.is_dense = false;
        cloud.resize(4);
        for (int i = 0; i < 4; ++i) {
            cloud[i].x = k_corners[i][0];
            cloud[i].y = k_corners[i][1];
            cloud[i].z = k_corners[i][2];
            cloud[i].normal_z = 1.f;
            cloud[i].r = static_cast<std::uint8_t>(50 * i);
        }
        pcl::io::savePCDFileBinaryCompressed((out / "pcd" / "compressed.pcd").string(), cloud);
#endif
        save_pool(out / "pool" / "points.pool", pool_full(false, false));
        save_pool(out / "pool" / "octree.pool", pool_full(true, false));
        save_pool(out / "pool" / "octree-unknown-section.pool", pool_full(true, true));
        save(out / "patches" / "grid.bpt", patch_grid(false));
        save(out / "patches" / "grid-newell.txt", patch_grid(true));
    } catch (const std::exception& e) {
        std::fprintf(stderr, "prt-fuzz-seeds: %s\n", e.what());
        return 1;
    }
    return 0;
}
