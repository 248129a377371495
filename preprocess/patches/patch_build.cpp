// prt-patches: orientation, subpatch trees, normal cones and the patch BVH (seed 002, 5.1).
#include "patch_build.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <numeric>
#include <utility>

#include "float_round.h"
#include "prt/core/bezier.h"
#include "prt/error.h"

namespace prt::patches {

using core::DVec3;
using core::dvec3;

namespace {

constexpr double k_pi = 3.14159265358979323846;

using pre::round_down;  // outward box bounds (float_round.h)
using pre::round_up;

double area(const Box& b) {
    const double dx = b.hi[0] - b.lo[0], dy = b.hi[1] - b.lo[1], dz = b.hi[2] - b.lo[2];
    return 2.0 * (dx * dy + dy * dz + dz * dx);
}

Box empty_box() {
    Box b;
    for (int a = 0; a < 3; ++a) {
        b.lo[a] = std::numeric_limits<double>::infinity();
        b.hi[a] = -std::numeric_limits<double>::infinity();
    }
    return b;
}

void grow(Box& b, const Box& o) {
    for (int a = 0; a < 3; ++a) {
        b.lo[a] = std::min(b.lo[a], o.lo[a]);
        b.hi[a] = std::max(b.hi[a], o.hi[a]);
    }
}

Box padded(const Box& b, double pad) {
    Box p = b;
    for (int a = 0; a < 3; ++a) {
        p.lo[a] -= pad;
        p.hi[a] += pad;
    }
    return p;
}

// ---- Orientation ------------------------------------------------------------------------------

/// The four boundary edges of a net as a counter-clockwise loop in (u, v): (0,0) -> (1,0) ->
/// (1,1) -> (0,1). Adjacent patches with the same orientation run a shared edge in opposite
/// directions.
std::array<int, 4> edge_indices(int edge) {
    switch (edge) {
        case 0:
            return {0, 4, 8, 12};  // v = 0, u from 0 to 1
        case 1:
            return {12, 13, 14, 15};  // u = 1, v from 0 to 1
        case 2:
            return {15, 11, 7, 3};  // v = 1, u from 1 to 0
        default:
            return {3, 2, 1, 0};  // u = 0, v from 1 to 0
    }
}

using EdgeKey = std::array<double, 12>;

bool same_point(const pool::PatchPoint& a, const pool::PatchPoint& b) {
    return a.x == b.x && a.y == b.y && a.z == b.z;
}

bool edge_collapsed(const pool::PatchControlNet& net, int edge) {
    const auto e = edge_indices(edge);
    return same_point(net.p[e[0]], net.p[e[1]]) && same_point(net.p[e[0]], net.p[e[2]]) &&
           same_point(net.p[e[0]], net.p[e[3]]);
}

/// Canonical key of an edge (the lexicographically smaller of its two directions) and whether
/// the patch runs it in the canonical direction.
std::pair<EdgeKey, bool> edge_key(const pool::PatchControlNet& net, int edge) {
    const auto e = edge_indices(edge);
    EdgeKey fwd{}, rev{};
    for (int k = 0; k < 4; ++k) {
        const pool::PatchPoint& p = net.p[e[k]];
        const pool::PatchPoint& q = net.p[e[3 - k]];
        fwd[3 * k] = p.x, fwd[3 * k + 1] = p.y, fwd[3 * k + 2] = p.z;
        rev[3 * k] = q.x, rev[3 * k + 1] = q.y, rev[3 * k + 2] = q.z;
    }
    if (std::lexicographical_compare(rev.begin(), rev.end(), fwd.begin(), fwd.end())) return {rev, false};
    return {fwd, true};
}

/// Integral of (Q - c) . (dQ/du x dQ/dv) over [0,1]^2 (midpoint rule, 8 x 8).
double signed_volume_term(const pool::PatchControlNet& net, DVec3 c) {
    constexpr int n = 8;
    double sum = 0.0;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            const core::PatchEval e = core::patch_eval(net, (i + 0.5) / n, (j + 0.5) / n);
            sum += core::dot(e.q - c, core::cross(e.qu, e.qv));
        }
    return sum / (n * n);
}

}  // namespace

Box net_bounds(const pool::PatchControlNet& net) {
    Box b = empty_box();
    for (const pool::PatchPoint& p : net.p) {
        const double c[3] = {p.x, p.y, p.z};
        for (int a = 0; a < 3; ++a) {
            b.lo[a] = std::min(b.lo[a], c[a]);
            b.hi[a] = std::max(b.hi[a], c[a]);
        }
    }
    return b;
}

void round_outwards(const Box& box, float lo[3], float hi[3]) {
    for (int a = 0; a < 3; ++a) {
        lo[a] = round_down(box.lo[a]);
        hi[a] = round_up(box.hi[a]);
    }
}

pool::PatchControlNet transpose_net(const pool::PatchControlNet& net) {
    pool::PatchControlNet t{};
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) t.p[4 * i + j] = net.p[4 * j + i];
    return t;
}

OrientStats orient_patches(std::vector<pool::PatchControlNet>& nets) {
    OrientStats st;
    const std::size_t n = nets.size();
    struct Use {
        std::uint32_t patch;
        bool canonical;
    };
    std::map<EdgeKey, std::vector<Use>> edges;
    for (std::size_t p = 0; p < n; ++p)
        for (int e = 0; e < 4; ++e) {
            if (edge_collapsed(nets[p], e)) {
                ++st.collapsed_edges;
                continue;
            }
            auto [key, canonical] = edge_key(nets[p], e);
            edges[key].push_back({static_cast<std::uint32_t>(p), canonical});
        }
    // Constraint graph: flip[p] xor flip[q] = (p and q run the shared edge the same way).
    std::vector<std::vector<std::pair<std::uint32_t, bool>>> adjacent(n);
    for (const auto& [key, uses] : edges) {
        if (uses.size() == 1) {
            ++st.boundary_edges;
        } else if (uses.size() == 2) {
            ++st.shared_edges;
            const bool same_direction = uses[0].canonical == uses[1].canonical;
            if (uses[0].patch == uses[1].patch) {
                if (same_direction) ++st.conflicts;  // a patch glued to itself the wrong way
                continue;
            }
            adjacent[uses[0].patch].push_back({uses[1].patch, same_direction});
            adjacent[uses[1].patch].push_back({uses[0].patch, same_direction});
        } else {
            ++st.nonmanifold_edges;
        }
    }
    // Model centre for the outward test.
    Box all = empty_box();
    for (const auto& net : nets) grow(all, net_bounds(net));
    const DVec3 centre{0.5 * (all.lo[0] + all.hi[0]), 0.5 * (all.lo[1] + all.hi[1]),
                       0.5 * (all.lo[2] + all.hi[2])};
    const double size = std::max({all.hi[0] - all.lo[0], all.hi[1] - all.lo[1], all.hi[2] - all.lo[2], 0.0});
    const double flat_volume = 1e-9 * size * size * size;

    std::vector<int> flip(n, -1);  // -1 unvisited, else 0/1
    std::vector<std::uint32_t> component;
    std::vector<std::uint32_t> queue;
    for (std::size_t seed = 0; seed < n; ++seed) {
        if (flip[seed] >= 0) continue;
        ++st.components;
        component.clear();
        queue.assign(1, static_cast<std::uint32_t>(seed));
        flip[seed] = 0;
        for (std::size_t qi = 0; qi < queue.size(); ++qi) {
            const std::uint32_t p = queue[qi];
            component.push_back(p);
            for (const auto& [q, same] : adjacent[p]) {
                const int want = flip[p] ^ (same ? 1 : 0);
                if (flip[q] < 0) {
                    flip[q] = want;
                    queue.push_back(q);
                } else if (flip[q] != want && p < q) {
                    ++st.conflicts;
                }
            }
        }
        double volume = 0.0;
        for (std::uint32_t p : component) {
            const pool::PatchControlNet net = flip[p] ? transpose_net(nets[p]) : nets[p];
            volume += signed_volume_term(net, centre);
        }
        // A group with no inside (a plane through the centre: a floor, a wall) has a signed volume
        // of rounding noise, whose sign would orient it at random: it keeps the file's orientation.
        if (volume < -flat_volume)
            for (std::uint32_t p : component) flip[p] ^= 1;
        else if (!(volume > flat_volume))
            ++st.flat_components;
    }
    for (std::size_t p = 0; p < n; ++p)
        if (flip[p] == 1) {
            nets[p] = transpose_net(nets[p]);
            ++st.flipped;
        }
    return st;
}

NormalCone normal_cone(const pool::PatchControlNet& net) {
    static constexpr double c2[3] = {1, 2, 1}, c3[4] = {1, 3, 3, 1}, c5[6] = {1, 5, 10, 10, 5, 1};
    DVec3 du[3][4], dv[4][3];
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 4; ++j) du[i][j] = dvec3(net.p[4 * (i + 1) + j]) - dvec3(net.p[4 * i + j]);
    for (int k = 0; k < 4; ++k)
        for (int l = 0; l < 3; ++l) dv[k][l] = dvec3(net.p[4 * k + l + 1]) - dvec3(net.p[4 * k + l]);
    DVec3 dirs[36];
    int count = 0;
    for (int a = 0; a <= 5; ++a)
        for (int b = 0; b <= 5; ++b) {
            DVec3 c{0, 0, 0};
            for (int i = std::max(0, a - 3); i <= std::min(2, a); ++i)
                for (int j = std::max(0, b - 2); j <= std::min(3, b); ++j) {
                    const int k = a - i, l = b - j;
                    const double w = c2[i] * c3[k] / c5[a] * (c3[j] * c2[l] / c5[b]);
                    c = c + core::cross(du[i][j], dv[k][l]) * w;
                }
            const double len = core::length(c);
            if (len > 0.0 && std::isfinite(len)) dirs[count++] = c * (1.0 / len);
        }
    NormalCone cone;
    if (count == 0) return cone;
    DVec3 sum{0, 0, 0};
    for (int i = 0; i < count; ++i) sum = sum + dirs[i];
    const double ls = core::length(sum);
    if (!(ls > 1e-9 * count)) return cone;
    const DVec3 axis = sum * (1.0 / ls);
    double max_angle = 0.0;
    for (int i = 0; i < count; ++i)
        max_angle = std::max(max_angle, std::acos(std::clamp(core::dot(axis, dirs[i]), -1.0, 1.0)));
    cone.axis[0] = axis.x, cone.axis[1] = axis.y, cone.axis[2] = axis.z;
    cone.half_angle = max_angle;
    cone.valid = max_angle < 0.5 * k_pi;
    return cone;
}

void store_cone(const NormalCone& cone, pool::SubpatchNode& node) {
    node.cone_axis = core::octahedral_encode(DVec3{0, 0, 1});
    node.cone_cos = -1.0f;
    if (!cone.valid) return;
    const DVec3 axis{cone.axis[0], cone.axis[1], cone.axis[2]};
    const std::uint32_t code = core::octahedral_encode(axis);
    const DVec3 decoded = core::octahedral_decode(code);
    // angle(decoded, n) <= angle(decoded, axis) + angle(axis, n): widen by the encoding error, and
    // a little for the rounding of the coefficients.
    const double widened =
        cone.half_angle + std::acos(std::clamp(core::dot(decoded, axis), -1.0, 1.0)) + 1e-6;
    if (!(widened < 0.5 * k_pi)) return;
    node.cone_axis = code;
    node.cone_cos = round_down(std::cos(widened));
    if (!(node.cone_cos > 0.0f)) node.cone_cos = -1.0f;
}

void build_subpatch_tree(const pool::PatchControlNet& net, std::uint32_t depth, double pad,
                         pool::SubpatchNode* out) {
    const std::uint32_t count = (2u << depth) - 1u;
    const std::uint32_t first_leaf = (1u << depth) - 1u;
    std::vector<pool::PatchControlNet> sub(count);
    sub[0] = net;
    for (std::uint32_t k = 0; k < count; ++k) {
        pool::SubpatchNode& node = out[k];
        round_outwards(padded(net_bounds(sub[k]), pad), node.lo, node.hi);
        store_cone(normal_cone(sub[k]), node);
        if (k < first_leaf)
            core::patch_split(sub[k], core::subpatch_split_axis(core::subpatch_level(k)), 0.5, sub[2 * k + 1],
                              sub[2 * k + 2]);
    }
}

// ---- BVH: binned SAH (seed 002, 5.1; Guenther et al. 2007) -------------------------------------

namespace {

std::uint32_t ceil_log2(std::uint64_t n) {
    std::uint32_t b = 0;
    while ((std::uint64_t{1} << b) < n) ++b;
    return b;
}

class BvhBuilder {
public:
    BvhBuilder(std::span<const Box> boxes, std::uint32_t bins, double pad)
        : m_boxes(boxes), m_bins(std::max<std::uint32_t>(bins, 2)), m_pad(pad) {
        m_index.resize(boxes.size());
        std::iota(m_index.begin(), m_index.end(), 0u);
        m_centroid.resize(boxes.size());
        for (std::size_t i = 0; i < boxes.size(); ++i)
            for (int a = 0; a < 3; ++a) m_centroid[i][a] = 0.5 * (boxes[i].lo[a] + boxes[i].hi[a]);
        m_nodes.reserve(boxes.empty() ? 0 : 2 * boxes.size() - 1);
    }

    std::vector<pool::PatchBvhNode> build(BvhStats* stats) {
        if (!m_boxes.empty()) {
            Box root = empty_box();
            for (const Box& b : m_boxes) grow(root, b);
            m_root_area = area(root);
            build(0, static_cast<std::uint32_t>(m_boxes.size()), 0);
        }
        if (stats) *stats = m_stats;
        return std::move(m_nodes);
    }

private:
    void build(std::uint32_t begin, std::uint32_t end, std::uint32_t depth) {
        m_stats.depth = std::max(m_stats.depth, depth);
        const std::uint32_t at = static_cast<std::uint32_t>(m_nodes.size());
        m_nodes.push_back({});
        Box bounds = empty_box();
        for (std::uint32_t i = begin; i < end; ++i) grow(bounds, m_boxes[m_index[i]]);
        if (m_root_area > 0.0) m_stats.sah_cost += area(bounds) / m_root_area;
        {
            pool::PatchBvhNode& node = m_nodes[at];
            round_outwards(padded(bounds, m_pad), node.lo, node.hi);
            node.patch = -1;
        }
        if (end - begin == 1) {
            m_nodes[at].patch = static_cast<std::int32_t>(m_index[begin]);
            m_nodes[at].skip = at + 1;
            return;
        }
        const std::uint32_t mid = split(begin, end, depth);
        build(begin, mid, depth + 1);
        build(mid, end, depth + 1);
        m_nodes[at].skip = static_cast<std::uint32_t>(m_nodes.size());
    }

    /// Partitions [begin, end) and returns the split position (strictly inside).
    std::uint32_t split(std::uint32_t begin, std::uint32_t end, std::uint32_t depth) {
        const std::uint32_t n = end - begin;
        double cmin[3], cmax[3];
        for (int a = 0; a < 3; ++a) {
            cmin[a] = std::numeric_limits<double>::infinity();
            cmax[a] = -cmin[a];
        }
        for (std::uint32_t i = begin; i < end; ++i)
            for (int a = 0; a < 3; ++a) {
                cmin[a] = std::min(cmin[a], m_centroid[m_index[i]][a]);
                cmax[a] = std::max(cmax[a], m_centroid[m_index[i]][a]);
            }
        // Depth guard: a median split halves the range, so the remaining levels always fit.
        const bool guard = depth + 1 + ceil_log2(n) >= pool::k_max_patch_bvh_depth;
        int best_axis = -1;
        std::uint32_t best_bin = 0;
        double best_cost = std::numeric_limits<double>::infinity();
        if (!guard) {
            std::vector<Box> bin_box(m_bins);
            std::vector<std::uint32_t> bin_count(m_bins);
            std::vector<double> right_area(m_bins);
            std::vector<std::uint32_t> right_count(m_bins);
            for (int a = 0; a < 3; ++a) {
                const double extent = cmax[a] - cmin[a];
                if (!(extent > 0.0)) continue;
                std::fill(bin_box.begin(), bin_box.end(), empty_box());
                std::fill(bin_count.begin(), bin_count.end(), 0u);
                for (std::uint32_t i = begin; i < end; ++i) {
                    const std::uint32_t b = bin_of(m_index[i], a, cmin[a], extent);
                    grow(bin_box[b], m_boxes[m_index[i]]);
                    ++bin_count[b];
                }
                // Sweep from the right, then from the left: cost = A_L N_L + A_R N_R.
                Box acc = empty_box();
                std::uint32_t cnt = 0;
                for (std::uint32_t b = m_bins; b-- > 1;) {
                    if (bin_count[b]) grow(acc, bin_box[b]);
                    cnt += bin_count[b];
                    right_area[b] = cnt ? area(acc) : 0.0;
                    right_count[b] = cnt;
                }
                acc = empty_box();
                cnt = 0;
                for (std::uint32_t b = 0; b + 1 < m_bins; ++b) {
                    if (bin_count[b]) grow(acc, bin_box[b]);
                    cnt += bin_count[b];
                    if (cnt == 0 || right_count[b + 1] == 0) continue;
                    const double cost = area(acc) * cnt + right_area[b + 1] * right_count[b + 1];
                    if (cost < best_cost) {
                        best_cost = cost;
                        best_axis = a;
                        best_bin = b;
                    }
                }
            }
        }
        if (best_axis >= 0) {
            const double extent = cmax[best_axis] - cmin[best_axis];
            const auto it = std::partition(
                m_index.begin() + begin, m_index.begin() + end,
                [&](std::uint32_t i) { return bin_of(i, best_axis, cmin[best_axis], extent) <= best_bin; });
            const auto mid = static_cast<std::uint32_t>(it - m_index.begin());
            if (mid > begin && mid < end) return mid;
        }
        // Median split along the widest centroid axis (coincident centroids, or the depth guard).
        ++m_stats.median_splits;
        int axis = 0;
        for (int a = 1; a < 3; ++a)
            if (cmax[a] - cmin[a] > cmax[axis] - cmin[axis]) axis = a;
        const std::uint32_t mid = begin + n / 2;
        std::nth_element(m_index.begin() + begin, m_index.begin() + mid, m_index.begin() + end,
                         [&](std::uint32_t x, std::uint32_t y) {
                             return m_centroid[x][axis] < m_centroid[y][axis] ||
                                    (m_centroid[x][axis] == m_centroid[y][axis] && x < y);
                         });
        return mid;
    }

    std::uint32_t bin_of(std::uint32_t i, int axis, double cmin, double extent) const {
        const double f = (m_centroid[i][axis] - cmin) / extent * m_bins;
        return std::min(m_bins - 1, static_cast<std::uint32_t>(std::max(0.0, f)));
    }

    std::span<const Box> m_boxes;
    std::uint32_t m_bins;
    double m_pad;
    double m_root_area = 0.0;
    std::vector<std::uint32_t> m_index;
    std::vector<std::array<double, 3>> m_centroid;
    std::vector<pool::PatchBvhNode> m_nodes;
    BvhStats m_stats;
};

}  // namespace

std::vector<pool::PatchBvhNode> build_patch_bvh(std::span<const Box> boxes, std::uint32_t bins, double pad,
                                                BvhStats* stats) {
    return BvhBuilder(boxes, bins, pad).build(stats);
}

PatchModel build_patch_model(std::vector<pool::PatchControlNet> nets, const BuildOptions& options,
                             const std::function<void(std::uint64_t, std::uint64_t)>& progress) {
    if (nets.empty()) throw Error("no patches to build");
    if (nets.size() > pool::k_max_patches)
        throw Error(std::to_string(nets.size()) + " patches exceed the limit of " +
                    std::to_string(pool::k_max_patches));
    if (options.depth > pool::k_max_subpatch_depth)
        throw Error("subpatch depth " + std::to_string(options.depth) + " exceeds the limit of " +
                    std::to_string(pool::k_max_subpatch_depth));
    const std::uint32_t per_patch = (2u << options.depth) - 1u;
    const std::uint64_t total_nodes = std::uint64_t(nets.size()) * per_patch;
    if (total_nodes > (std::uint64_t{1} << 31))
        throw Error(std::to_string(nets.size()) + " patches x " + std::to_string(per_patch) +
                    " subpatch boxes exceed 2^31 boxes: lower --depth");
    for (const auto& net : nets)
        for (const auto& p : net.p)
            if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
                throw Error("a control point is not finite");

    PatchModel m;
    for (const auto& net : nets)
        for (int e = 0; e < 4; ++e)
            if (edge_collapsed(net, e)) {
                ++m.degenerate_patches;
                break;
            }
    if (options.orient) m.orient = orient_patches(nets);

    Box world = empty_box();
    for (const auto& net : nets) grow(world, net_bounds(net));
    const double origin[3] = {0.5 * (world.lo[0] + world.hi[0]), 0.5 * (world.lo[1] + world.hi[1]),
                              0.5 * (world.lo[2] + world.hi[2])};
    double extent = 0.0;
    for (int a = 0; a < 3; ++a) extent = std::max(extent, world.hi[a] - world.lo[a]);
    if (!(extent > 0.0)) extent = 1.0;
    // Boxes grow by this much before rounding to float: covers the float rounding of ray origins
    // up to ~10 model sizes away (traversal runs in float, seed 002, 6).
    const double pad = 1e-6 * extent;

    m.nets = std::move(nets);
    Box local = empty_box();
    for (auto& net : m.nets)
        for (auto& p : net.p) {
            p.x -= origin[0];
            p.y -= origin[1];
            p.z -= origin[2];
            const double c[3] = {p.x, p.y, p.z};
            for (int a = 0; a < 3; ++a) {
                local.lo[a] = std::min(local.lo[a], c[a]);
                local.hi[a] = std::max(local.hi[a], c[a]);
            }
        }

    const std::uint64_t n = m.nets.size();
    m.nodes.resize(total_nodes);
    std::vector<Box> boxes(n);
    for (std::uint64_t p = 0; p < n; ++p) {
        build_subpatch_tree(m.nets[p], options.depth, pad, m.nodes.data() + p * per_patch);
        boxes[p] = net_bounds(m.nets[p]);
        if (progress) progress(p + 1, n);
    }
    m.bvh = build_patch_bvh(boxes, options.bins, pad, &m.bvh_stats);

    pool::ModelInfo& mi = m.model_info;
    std::memset(&mi, 0, sizeof mi);
    for (int a = 0; a < 3; ++a) mi.origin[a] = origin[a];
    round_outwards(local, mi.bounds_min, mi.bounds_max);
    mi.point_count = 0;

    pool::PatchInfo& pi = m.patch_info;
    std::memset(&pi, 0, sizeof pi);
    pi.patch_count = static_cast<std::uint32_t>(n);
    pi.bvh_node_count = static_cast<std::uint32_t>(m.bvh.size());
    pi.subpatch_depth = options.depth;
    pi.subpatch_nodes = per_patch;
    pi.bvh_depth = m.bvh_stats.depth;
    // Oriented only when every shared edge is consistent and manifold: an edge of three or more
    // patches (duplicated patches, fins) leaves the side ambiguous.
    pi.flags = (options.orient && m.orient.conflicts == 0 && m.orient.nonmanifold_edges == 0)
                   ? pool::k_patch_oriented
                   : 0u;
    round_outwards(local, pi.bounds_min, pi.bounds_max);
    return m;
}

void write_patch_sections(const PatchModel& model, pool::PoolWriter& writer) {
    writer.add_array(pool::SectionType::model_info, std::vector<pool::ModelInfo>{model.model_info});
    writer.add_array(pool::SectionType::patch_info, std::vector<pool::PatchInfo>{model.patch_info});
    writer.add_array(pool::SectionType::patch_control_points, model.nets);
    writer.add_array(pool::SectionType::patch_bvh, model.bvh);
    writer.add_array(pool::SectionType::patch_subpatch_boxes, model.nodes);
}

}  // namespace prt::patches
