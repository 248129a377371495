// prt-import: scan or mesh -> pool (model_info, positions, normals, colors, radii).
#include <cstdio>
#include <string>
#include <vector>

#include "import.h"
#include "prt/formats/pool.h"
#include "prt/tool.h"

namespace imp = prt::pre::import;

int main(int argc, char** argv) {
    std::string input;
    std::string output;
    std::string format = "auto";
    std::string normals = "auto";
    std::string mesh_mode = "auto";
    std::string sample_normals = "face";
    std::vector<double> sensor;
    imp::Options options;

    auto setup = [&](CLI::App& app, prt::tool::CommonOptions&) {
        app.footer(
            "Formats: PLY (ascii, binary little/big endian; vertex x y z, optional nx ny nz, red green blue\n"
            "[alpha] as uchar or float 0..1, radius; other properties and elements skipped), XYZ text\n"
            "(x y z or x y z nx ny nz per line, space or comma separated, # comments), PCD (via PCL;\n"
            "x y z, optional normal_x.., rgb/rgba; NaN entries of organized clouds dropped), meshes\n"
            "(PLY with faces, OBJ, OFF, STL via OpenMesh: vertices with area-weighted normals, or "
            "--sample).\n"
            "Normals: estimated by PCA over k neighbours when missing (needs PCL), oriented toward --sensor\n"
            "or by propagation over the k-NN graph (Hoppe 1992) from each component's highest point (+z\n"
            "outward). Dropped points (NaN/Inf, zero normals, duplicates, malformed lines) are counted on\n"
            "stderr. On any error nothing is written and the exit code is 1 (2 for bad usage).");
        app.add_option("input", input, "Scan or mesh to import (.ply .pcd .xyz .txt .obj .off .stl)")
            ->required();
        app.add_option("-o,--output", output, "Pool file to write (written atomically)")->required();
        app.add_option("--format", format,
                       "Input format: auto (by extension, then by content), ply, pcd, xyz, mesh")
            ->check(CLI::IsMember({"auto", "ply", "pcd", "xyz", "mesh"}));
        app.add_option("--normals", normals,
                       "auto: keep the file's normals, estimate by PCA only when it has none (meshes: "
                       "area-weighted vertex normals, the file's where faces cancel); keep: never estimate "
                       "(a file without normals gives a pool without normals; meshes: the file's vertex "
                       "normals, area-weighted where it has none); estimate: always PCA, ignoring the file's")
            ->check(CLI::IsMember({"auto", "keep", "estimate"}));
        app.add_option("--mesh-mode", mesh_mode,
                       "A PLY with faces is read as: auto (a mesh when it has faces and no vertex normals, "
                       "else points; points when this build lacks OpenMesh), points (the vertex element "
                       "only), mesh (through OpenMesh)")
            ->check(CLI::IsMember({"auto", "points", "mesh"}));
        app.add_option("--sample", options.sample,
                       "Meshes: sample this many points uniformly over the surface by area instead of "
                       "taking the vertices (0 = vertices)");
        app.add_option("--seed", options.seed, "Random seed for --sample (same seed, same points)");
        app.add_option("--sample-normals", sample_normals,
                       "Normals of sampled points: face (the normal of the triangle sampled) or "
                       "interpolated (area-weighted vertex normals blended barycentrically)")
            ->check(CLI::IsMember({"face", "interpolated"}));
        app.add_option("-k,--k", options.k, "Neighbours for PCA normal estimation and orientation")
            ->check(CLI::Range(3, 256));
        app.add_option("--sensor", sensor,
                       "X,Y,Z: orient estimated normals toward this point (the scanner position) "
                       "instead of propagating over the k-NN graph (default: none, propagate)")
            ->delimiter(',')
            ->expected(3);
        app.add_flag("--keep-duplicates", options.keep_duplicates,
                     "Keep exactly coincident points (default: keep the first, drop and count the rest)");
    };

    auto body = [&](const prt::tool::CommonOptions& common) {
        options.quiet = common.quiet;
        options.format = format == "ply"    ? imp::Format::ply
                         : format == "pcd"  ? imp::Format::pcd
                         : format == "xyz"  ? imp::Format::xyz
                         : format == "mesh" ? imp::Format::mesh
                                            : imp::Format::automatic;
        options.normals = normals == "keep"       ? imp::NormalsMode::keep
                          : normals == "estimate" ? imp::NormalsMode::estimate
                                                  : imp::NormalsMode::automatic;
        options.mesh_mode = mesh_mode == "points" ? imp::MeshMode::points
                            : mesh_mode == "mesh" ? imp::MeshMode::mesh
                                                  : imp::MeshMode::automatic;
        options.sample_normals =
            sample_normals == "interpolated" ? imp::SampleNormals::interpolated : imp::SampleNormals::face;
        if (sensor.size() == 3) options.sensor = std::array<double, 3>{sensor[0], sensor[1], sensor[2]};

        imp::Report report;
        const prt::pre::PointCloud cloud = imp::import_file(input, options, report);
        prt::pool::PoolWriter writer;
        prt::pre::write_point_sections(cloud, writer);
        writer.add_provenance("prt-import", PRT_VERSION, imp::options_json(input, options));
        const double t0 = prt::tool::now_seconds();
        const std::uint64_t bytes = writer.write(output);
        for (const std::string& line : report.summary_lines())
            prt::tool::note(common.quiet, "%s", line.c_str());
        prt::tool::note(common.quiet, "wrote %s: %llu points%s%s%s, %llu bytes in %.3f s", output.c_str(),
                        static_cast<unsigned long long>(cloud.size()), cloud.has_normals() ? ", normals" : "",
                        cloud.has_colors() ? ", colors" : "", cloud.has_radii() ? ", radii" : "",
                        static_cast<unsigned long long>(bytes), prt::tool::now_seconds() - t0);
    };

    return prt::tool::run(argc, argv, "prt-import",
                          "Imports a scan (PLY, XYZ, PCD) or a mesh (PLY, OBJ, OFF, STL) into a pool file",
                          setup, body);
}
