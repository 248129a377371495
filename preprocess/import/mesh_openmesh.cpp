// The one translation unit that includes OpenMesh: its reader modules parse PLY/OBJ/OFF/STL into
// a BaseImporter of ours that keeps plain vertex and face arrays (no halfedge structure, so no
// face is dropped or vertex duplicated for being non-manifold).
#include "mesh.h"

#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/IO/importer/BaseImporter.hh>
#include <algorithm>
#include <cctype>
#include <iostream>
#include <sstream>

#include "progress.h"
#include "prt/error.h"

namespace prt::pre::import {

namespace {

namespace om = OpenMesh;

class PlainImporter final : public om::IO::BaseImporter {
public:
    explicit PlainImporter(MeshData& mesh) : m_mesh(mesh) { m_mesh.face_begin.assign(1, 0); }

    std::uint64_t invalid_faces = 0;
    std::uint64_t normals_set = 0;
    std::uint64_t colors_set = 0;

    om::VertexHandle add_vertex(const om::Vec3f& p) override {
        return add_vertex(om::Vec3d(p[0], p[1], p[2]));
    }
    om::VertexHandle add_vertex(const om::Vec3d& p) override {
        m_mesh.vertices.push_back({p[0], p[1], p[2]});
        return om::VertexHandle(static_cast<int>(m_mesh.vertices.size() - 1));
    }
    om::VertexHandle add_vertex() override { return add_vertex(om::Vec3d(0, 0, 0)); }
    om::HalfedgeHandle add_edge(om::VertexHandle, om::VertexHandle) override { return om::HalfedgeHandle(); }
    om::FaceHandle add_face(const VHandles& indices) override {
        if (indices.size() < 3) {
            ++invalid_faces;
            return om::FaceHandle();
        }
        for (const om::VertexHandle& v : indices)
            if (v.idx() < 0 || static_cast<std::size_t>(v.idx()) >= m_mesh.vertices.size()) {
                ++invalid_faces;
                return om::FaceHandle();
            }
        for (const om::VertexHandle& v : indices)
            m_mesh.face_indices.push_back(static_cast<std::uint32_t>(v.idx()));
        m_mesh.face_begin.push_back(static_cast<std::uint32_t>(m_mesh.face_indices.size()));
        return om::FaceHandle(static_cast<int>(m_mesh.face_begin.size() - 2));
    }
    om::FaceHandle add_face(om::HalfedgeHandle) override { return om::FaceHandle(); }
    void add_face_texcoords(om::FaceHandle, om::VertexHandle, const std::vector<om::Vec2f>&) override {}
    void add_face_texcoords(om::FaceHandle, om::VertexHandle, const std::vector<om::Vec3f>&) override {}
    void set_face_texindex(om::FaceHandle, int) override {}
    void set_point(om::VertexHandle v, const om::Vec3f& p) override {
        if (in_range(v)) m_mesh.vertices[v.idx()] = {p[0], p[1], p[2]};
    }
    void set_halfedge(om::VertexHandle, om::HalfedgeHandle) override {}
    void set_normal(om::VertexHandle v, const om::Vec3f& n) override {
        set_normal(v, om::Vec3d(n[0], n[1], n[2]));
    }
    void set_normal(om::VertexHandle v, const om::Vec3d& n) override {
        if (!in_range(v)) return;
        if (m_mesh.vertex_normals.size() < m_mesh.vertices.size())
            m_mesh.vertex_normals.resize(m_mesh.vertices.size(), {0.f, 0.f, 0.f});
        m_mesh.vertex_normals[v.idx()] = {static_cast<float>(n[0]), static_cast<float>(n[1]),
                                          static_cast<float>(n[2])};
        ++normals_set;
    }
    void set_color(om::VertexHandle v, const om::Vec3uc& c) override {
        store_color(v, {c[0], c[1], c[2], 255});
    }
    void set_color(om::VertexHandle v, const om::Vec4uc& c) override {
        store_color(v, {c[0], c[1], c[2], c[3]});
    }
    void set_color(om::VertexHandle v, const om::Vec3f& c) override {
        store_color(v, {channel(c[0]), channel(c[1]), channel(c[2]), 255});
    }
    void set_color(om::VertexHandle v, const om::Vec4f& c) override {
        store_color(v, {channel(c[0]), channel(c[1]), channel(c[2]), channel(c[3])});
    }
    void set_texcoord(om::VertexHandle, const om::Vec2f&) override {}
    void set_status(om::VertexHandle, const om::Attributes::StatusInfo&) override {}
    void set_next(om::HalfedgeHandle, om::HalfedgeHandle) override {}
    void set_face(om::HalfedgeHandle, om::FaceHandle) override {}
    void request_face_texcoords2D() override {}
    void set_texcoord(om::HalfedgeHandle, const om::Vec2f&) override {}
    void set_texcoord(om::VertexHandle, const om::Vec3f&) override {}
    void set_texcoord(om::HalfedgeHandle, const om::Vec3f&) override {}
    void set_status(om::HalfedgeHandle, const om::Attributes::StatusInfo&) override {}
    void set_color(om::EdgeHandle, const om::Vec3uc&) override {}
    void set_color(om::EdgeHandle, const om::Vec4uc&) override {}
    void set_color(om::EdgeHandle, const om::Vec3f&) override {}
    void set_color(om::EdgeHandle, const om::Vec4f&) override {}
    void set_status(om::EdgeHandle, const om::Attributes::StatusInfo&) override {}
    void set_normal(om::FaceHandle, const om::Vec3f&) override {}
    void set_normal(om::FaceHandle, const om::Vec3d&) override {}
    void set_color(om::FaceHandle, const om::Vec3uc&) override {}
    void set_color(om::FaceHandle, const om::Vec4uc&) override {}
    void set_color(om::FaceHandle, const om::Vec3f&) override {}
    void set_color(om::FaceHandle, const om::Vec4f&) override {}
    void set_status(om::FaceHandle, const om::Attributes::StatusInfo&) override {}
    void add_texture_information(int, std::string) override {}
    void reserve(unsigned int vertices, unsigned int, unsigned int faces) override {
        // Counts come from the file's header: cap them so a lying header cannot exhaust memory.
        m_mesh.vertices.reserve(std::min(vertices, 1u << 26));
        m_mesh.face_begin.reserve(std::min(faces, 1u << 26) + 1u);
    }
    std::size_t n_vertices() const override { return m_mesh.vertices.size(); }
    std::size_t n_faces() const override { return m_mesh.face_count(); }
    std::size_t n_edges() const override { return 0; }

private:
    bool in_range(om::VertexHandle v) const {
        return v.idx() >= 0 && static_cast<std::size_t>(v.idx()) < m_mesh.vertices.size();
    }
    static std::uint8_t channel(float f) {
        const float c = f * 255.f + 0.5f;
        return c <= 0.f ? 0 : c >= 255.f ? 255 : static_cast<std::uint8_t>(c);  // NaN -> 255 is fine
    }
    void store_color(om::VertexHandle v, pool::Rgba8 c) {
        if (!in_range(v)) return;
        if (m_mesh.vertex_colors.size() < m_mesh.vertices.size())
            m_mesh.vertex_colors.resize(m_mesh.vertices.size(), {0, 0, 0, 255});
        m_mesh.vertex_colors[v.idx()] = c;
        ++colors_set;
    }

    MeshData& m_mesh;
};

/// Routes OpenMesh's own messages (omerr, omlog, omout) into a string for the duration of a read.
/// Those streams (and OpenMesh's direct prints) write through std::cerr, std::clog and std::cout,
/// whose buffers are swapped for the string's here. (Reconnecting the mostreams instead leaks:
/// OpenMesh 9.0's mostream::disconnect drops its target without deleting it, 16 bytes per call,
/// found by the fuzzer's leak check.)
class CaptureOpenMeshLog {
public:
    CaptureOpenMeshLog()
        : m_cerr(std::cerr.rdbuf(m_text.rdbuf())),
          m_clog(std::clog.rdbuf(m_text.rdbuf())),
          m_cout(std::cout.rdbuf(m_text.rdbuf())) {}
    ~CaptureOpenMeshLog() {
        for (om::mostream* s : streams()) s->flush();  // a partial line stays in the capture
        std::cerr.rdbuf(m_cerr);
        std::clog.rdbuf(m_clog);
        std::cout.rdbuf(m_cout);
    }
    /// The first non-empty line OpenMesh printed.
    std::string first_line() {
        for (om::mostream* s : streams()) s->flush();
        std::istringstream in(m_text.str());
        std::string line;
        while (std::getline(in, line))
            if (line.find_first_not_of(" \t\r") != std::string::npos) return line;
        return {};
    }

private:
    static std::array<om::mostream*, 3> streams() { return {&::omerr(), &::omlog(), &::omout()}; }
    std::ostringstream m_text;  // declared first: the buffers below are swapped for its buffer
    std::streambuf* m_cerr;
    std::streambuf* m_clog;
    std::streambuf* m_cout;
};

}  // namespace

bool have_openmesh() {
    return true;
}

MeshData read_mesh(const std::filesystem::path& path, Report& report, bool quiet) {
    const std::string label = path.string();
    std::string ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    if (ext != ".ply" && ext != ".obj" && ext != ".off" && ext != ".stl")
        throw Error(label +
                    ": mesh import reads .ply, .obj, .off and .stl files (OpenMesh picks the format "
                    "by extension)");
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) throw Error(label + ": is a directory, not a file");
    const auto size = std::filesystem::file_size(path, ec);
    if (ec) throw Error(label + ": cannot open: " + ec.message());
    if (size == 0) throw Error(label + ": file is empty");

    MeshData mesh;
    PlainImporter importer(mesh);
    om::IO::Options options(om::IO::Options::VertexNormal | om::IO::Options::VertexColor);
    LazyProgress progress("reading " + label, 1, quiet);
    bool ok = false;
    std::string message;
    {
        CaptureOpenMeshLog capture;
        try {
            ok = om::IO::IOManager().read(label, importer, options);
        } catch (const std::exception& e) {
            ok = false;
            message = e.what();
        }
        if (!ok && message.empty()) message = capture.first_line();
    }
    progress.finish();
    if (!ok)
        throw Error(label + ": OpenMesh could not read the mesh" +
                    (message.empty() ? "" : " (" + message + ")"));
    if (mesh.vertices.empty())
        throw Error(label + ": no vertices read (an empty mesh, or not a valid " + ext.substr(1) + " file)");
    if (mesh.face_count() == 0) throw Error(label + ": the mesh has no faces (import it as a point set)");
    if (mesh.vertex_normals.size() != mesh.vertices.size() || importer.normals_set == 0)
        mesh.vertex_normals.clear();
    if (mesh.vertex_colors.size() != mesh.vertices.size() || importer.colors_set == 0)
        mesh.vertex_colors.clear();
    report.faces = mesh.face_count();
    report.faces_invalid = importer.invalid_faces;
    report.reader = "mesh (OpenMesh, " + ext.substr(1) + ")";
    return mesh;
}

}  // namespace prt::pre::import
