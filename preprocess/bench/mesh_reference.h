// PointRT fidelity measurement (issue 15): the reference surface, ray cast by code independent of
// the surfaces under test. A triangle mesh (the Stanford bunny's zippered reconstruction, the
// meshes the armadillo and dragon points come from) in a plain bounding volume hierarchy, all in
// double: closest ray hit (two-sided, Moller-Trumbore) and closest point (Ericson, "Real-Time
// Collision Detection" 5.1.5), with normals interpolated from area-weighted vertex normals.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "prt/vec3.h"

namespace prt::bench {

using D3 = Vec3d;

/// A ray's first hit on the mesh.
struct MeshHit {
    double t = 0;
    D3 point{};
    D3 normal{};        ///< interpolated vertex normal, unit, as oriented (see MeshReference)
    bool front = true;  ///< the ray meets the side the (oriented) face normal points to
};

class MeshReference {
public:
    /// Triangles (a, b, c vertex indices; polygons must be fanned by the caller). Degenerate
    /// triangles are dropped. The mesh is oriented so that its signed volume is positive (normals
    /// outward for a closed or nearly closed surface); `flipped()` says whether that turned it.
    /// Throws prt::Error when no triangle is left.
    MeshReference(std::vector<D3> vertices, std::vector<std::array<std::uint32_t, 3>> triangles);

    /// First hit with t in (0, t_max] of o + t d (d need not be unit).
    bool intersect(const D3& o, const D3& d, double t_max, MeshHit& hit) const;
    /// Distance from p to the nearest point of the mesh.
    double distance(const D3& p) const;

    std::size_t triangle_count() const { return m_tris.size(); }
    bool flipped() const { return m_flipped; }
    D3 bounds_min() const { return m_lo; }
    D3 bounds_max() const { return m_hi; }

private:
    struct Node {
        D3 lo, hi;
        std::uint32_t first;  ///< leaf: first triangle in m_order; inner: left child (right = +1)
        std::uint32_t count;  ///< leaf: triangle count; 0 for an inner node
    };
    std::vector<D3> m_vertices;
    std::vector<D3> m_vertex_normals;
    std::vector<std::array<std::uint32_t, 3>> m_tris;
    std::vector<Node> m_nodes;
    D3 m_lo{}, m_hi{};
    bool m_flipped = false;
};

}  // namespace prt::bench
