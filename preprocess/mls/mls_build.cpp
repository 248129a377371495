// PointRT preprocess: the MLS kd-tree build (WS05 3.4), see mls_build.h.
#include "mls_build.h"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>

#include "float_round.h"
#include "mls_bvh.h"
#include "morton.h"
#include "prt/error.h"
#include "prt/parallel.h"
#include "prt/tool_util.h"
#include "radix_sort.h"

namespace prt::mls {

namespace {

/// Split nodes shrinking may insert above one leaf: a low and a high cut per axis.
constexpr std::uint32_t k_max_shrink_splits = 6;
/// Hull bound (pairs of splats) only for boxes with at most this many splats: O(n^2).
constexpr std::size_t k_pair_bound_max = 64;
/// A slice whose classification needs more boxes than this is kept (conservative, bounds time).
constexpr std::uint64_t k_max_boxes_per_slice = 4096;

/// A build node. Children always have larger indices than their parent (appended after it), so
/// a pass over decreasing indices is a post-order pass (post-collapse).
struct BNode {
    Box box{};
    int axis = -1;  ///< -1: leaf
    float split = 0.0f;
    std::uint32_t child[2] = {0, 0};
    std::vector<std::uint32_t> refs;  ///< leaves only
};

double area(const Box& b) {
    const double x = b.hi[0] - b.lo[0], y = b.hi[1] - b.lo[1], z = b.hi[2] - b.lo[2];
    return 2.0 * (x * y + y * z + z * x);
}

double volume(const Box& b) {
    return (b.hi[0] - b.lo[0]) * (b.hi[1] - b.lo[1]) * (b.hi[2] - b.lo[2]);
}

double support_radius(const pool::MlsSplat& s) {
    return 1.0 / double(s.inv_support);
}

double pos(const pool::MlsSplat& s, int a) {
    return a == 0 ? s.position.x : (a == 1 ? s.position.y : s.position.z);
}
double nrm(const pool::MlsSplat& s, int a) {
    return a == 0 ? s.normal.x : (a == 1 ? s.normal.y : s.normal.z);
}

using pre::round_down;  // outward box bounds (float_round.h)
using pre::round_up;

/// Squared distance from p to the box (0 inside) and to its farthest corner.
void box_distances(const pool::MlsSplat& s, const Box& b, double& near2, double& far2) {
    near2 = 0.0;
    far2 = 0.0;
    for (int a = 0; a < 3; ++a) {
        const double p = pos(s, a);
        const double below = b.lo[a] - p, above = p - b.hi[a];
        const double d = std::max({below, above, 0.0});
        near2 += d * d;
        const double f = std::max(std::abs(p - b.lo[a]), std::abs(p - b.hi[a]));
        far2 += f * f;
    }
}

/// WS05 3.4.1 with interval arithmetic: whether F provably has no zero with W > 0 in the box.
bool proven_free(const Box& b, std::span<const pool::MlsSplat> splats,
                 std::span<const std::uint32_t> subset) {
    if (subset.empty()) return true;  // W = 0 everywhere in the box: no surface
    // Bound 1: interval extension of eq. 2, F = (sum w_i (x - p_i)) . (sum w_i n_i), with
    // w_i in [1 - dmax/R, 1 - dmin/R] clamped at 0 and x - p_i in the box minus p_i.
    double a_lo[3] = {0, 0, 0}, a_hi[3] = {0, 0, 0}, n_lo[3] = {0, 0, 0}, n_hi[3] = {0, 0, 0};
    for (const std::uint32_t i : subset) {
        const pool::MlsSplat& s = splats[i];
        double near2, far2;
        box_distances(s, b, near2, far2);
        const double inv = s.inv_support;
        const double w_hi = std::max(0.0, 1.0 - std::sqrt(near2) * inv);
        const double w_lo = std::max(0.0, 1.0 - std::sqrt(far2) * inv);
        for (int a = 0; a < 3; ++a) {
            const double e0 = b.lo[a] - pos(s, a), e1 = b.hi[a] - pos(s, a);
            a_lo[a] += e0 >= 0.0 ? w_lo * e0 : w_hi * e0;
            a_hi[a] += e1 >= 0.0 ? w_hi * e1 : w_lo * e1;
            const double n = nrm(s, a);
            n_lo[a] += n >= 0.0 ? w_lo * n : w_hi * n;
            n_hi[a] += n >= 0.0 ? w_hi * n : w_lo * n;
        }
    }
    double f_lo = 0.0, f_hi = 0.0;
    for (int a = 0; a < 3; ++a) {
        const double c[4] = {a_lo[a] * n_lo[a], a_lo[a] * n_hi[a], a_hi[a] * n_lo[a], a_hi[a] * n_hi[a]};
        f_lo += std::min({c[0], c[1], c[2], c[3]});
        f_hi += std::max({c[0], c[1], c[2], c[3]});
    }
    if (f_lo > 0.0 || f_hi < 0.0) return true;

    // Bound 2: f = F / W^2 = sum_ij l_i l_j (x - p_i) . n_j with l_i = w_i / W a partition of unity,
    // so f lies between the smallest and largest (x - p_i) . n_j over the box and over the pairs
    // of splats reaching it. Unlike bound 1 it does not degrade where the weights vanish.
    if (subset.size() > k_pair_bound_max) return false;
    double c[3], h[3];
    for (int a = 0; a < 3; ++a) {
        c[a] = 0.5 * (b.lo[a] + b.hi[a]);
        h[a] = 0.5 * (b.hi[a] - b.lo[a]);
    }
    double lo = std::numeric_limits<double>::infinity(), hi = -std::numeric_limits<double>::infinity();
    for (const std::uint32_t j : subset) {
        const pool::MlsSplat& sj = splats[j];
        const double nx = sj.normal.x, ny = sj.normal.y, nz = sj.normal.z;
        double pmax = -std::numeric_limits<double>::infinity(),
               pmin = std::numeric_limits<double>::infinity();
        for (const std::uint32_t i : subset) {
            const pool::MlsSplat& si = splats[i];
            const double pn = si.position.x * nx + si.position.y * ny + si.position.z * nz;
            pmax = std::max(pmax, pn);
            pmin = std::min(pmin, pn);
        }
        const double cn = c[0] * nx + c[1] * ny + c[2] * nz;
        const double hn = h[0] * std::abs(nx) + h[1] * std::abs(ny) + h[2] * std::abs(nz);
        lo = std::min(lo, cn - hn - pmax);
        hi = std::max(hi, cn + hn - pmin);
        if (lo <= 0.0 && hi >= 0.0) return false;  // both signs possible already
    }
    return lo > 0.0 || hi < 0.0;
}

/// Morton code of a point quantized to 21 bits per axis inside [lo, hi], x in the highest bit of
/// each triplet (morton3 with the axes reversed: the order of the stored splats follows from it).
std::uint64_t morton(const double p[3], const double lo[3], const double hi[3]) {
    std::uint32_t q[3];
    for (int a = 0; a < 3; ++a) {
        const double ext = hi[a] - lo[a];
        const double u = ext > 0.0 ? (p[a] - lo[a]) / ext : 0.0;
        q[a] = static_cast<std::uint32_t>(std::clamp(u, 0.0, 1.0) * 2097151.0);
    }
    return pre::morton3(q[2], q[1], q[0]);
}

/// Pass 1 for one subtree: SAH splits (WS05 3.4 eq. 3, with E(n) of 3.4.2) until the leaf cost
/// wins or max_depth. `nodes[0]` is the subtree root on entry (box and refs set).
struct SahBuilder {
    std::span<const pool::MlsSplat> splats;
    std::span<const Box> boxes;  ///< support box per splat
    const BuildOptions& opt;

    double cell_cost(std::uint64_t n) const {
        return opt.cost_intersection * double(n) *
               (opt.encourage ? encourage_factor(n, opt.encourage_limit) : 1.0);
    }

    /// Returns true and the split when splitting beats making a leaf.
    bool find_split(const BNode& node, int& best_axis, float& best_split) const {
        const std::size_t n = node.refs.size();
        const double sa = area(node.box);
        if (n == 0 || !(sa > 0.0)) return false;
        double best = cell_cost(n);
        best_axis = -1;
        std::vector<double> los(n), his(n);
        for (int a = 0; a < 3; ++a) {
            const double lo = node.box.lo[a], hi = node.box.hi[a];
            if (!(hi > lo)) continue;
            for (std::size_t k = 0; k < n; ++k) {
                const Box& sb = boxes[node.refs[k]];
                los[k] = std::max(sb.lo[a], lo);
                his[k] = std::min(sb.hi[a], hi);
            }
            std::sort(los.begin(), los.end());
            std::sort(his.begin(), his.end());
            Box left = node.box, right = node.box;
            std::size_t i = 0, j = 0;
            while (i < n || j < n) {
                const double event = (j >= n || (i < n && los[i] < his[j])) ? los[i] : his[j];
                const float sf = static_cast<float>(event);  // split planes are floats in the pool
                const double s = sf;
                while (i < n && los[i] < s) ++i;
                std::size_t jj = j;
                while (jj < n && his[jj] <= s) ++jj;
                if (s > lo && s < hi) {
                    const std::size_t nl = i, nr = n - jj;  // boxes reaching below / above s
                    left.hi[a] = s;
                    right.lo[a] = s;
                    const double cost =
                        opt.cost_traversal + (area(left) * cell_cost(nl) + area(right) * cell_cost(nr)) / sa;
                    if (cost < best) {
                        best = cost;
                        best_axis = a;
                        best_split = sf;
                    }
                }
                while (i < n && los[i] <= std::max(s, event)) ++i;
                j = jj;
                while (j < n && his[j] <= std::max(s, event)) ++j;
            }
        }
        return best_axis >= 0;
    }

    void build(std::vector<BNode>& nodes, std::uint32_t root_depth) const {
        std::vector<std::pair<std::uint32_t, std::uint32_t>> stack{{0u, root_depth}};
        while (!stack.empty()) {
            const auto [index, depth] = stack.back();
            stack.pop_back();
            int axis;
            float split;
            if (depth >= opt.max_depth || !find_split(nodes[index], axis, split)) continue;  // a leaf
            split_node(nodes, index, axis, split);
            stack.push_back({nodes[index].child[1], depth + 1});
            stack.push_back({nodes[index].child[0], depth + 1});
        }
    }

    /// Makes nodes[index] an inner node; its refs go to the children whose cells the supports reach.
    void split_node(std::vector<BNode>& nodes, std::uint32_t index, int axis, float split) const {
        BNode l, r;
        l.box = r.box = nodes[index].box;
        l.box.hi[axis] = split;
        r.box.lo[axis] = split;
        for (const std::uint32_t s : nodes[index].refs) {
            if (support_overlaps(splats[s], l.box)) l.refs.push_back(s);
            if (support_overlaps(splats[s], r.box)) r.refs.push_back(s);
        }
        BNode& parent = nodes[index];
        parent.axis = axis;
        parent.split = split;
        parent.refs = {};
        const auto first = static_cast<std::uint32_t>(nodes.size());
        nodes[index].child[0] = first;
        nodes[index].child[1] = first + 1;
        nodes.push_back(std::move(l));
        nodes.push_back(std::move(r));
    }
};

/// A cut shrinking inserts: on `axis`, keep x >= value (low) or x <= value (high).
struct Cut {
    int axis;
    bool low;
    float value;
};

struct ShrinkOutcome {
    bool empty = false;
    Box box{};
    std::vector<std::uint32_t> refs;
    std::vector<Cut> cuts;
    std::uint64_t boxes = 0;
};

/// WS05 3.4.1: slices the leaf along the dominant normal axis (then the others) into K slices and
/// cuts off the slices at both ends that provably hold no surface.
ShrinkOutcome shrink_leaf(const BNode& leaf, std::span<const pool::MlsSplat> splats,
                          const BuildOptions& opt) {
    ShrinkOutcome out;
    out.box = leaf.box;
    out.refs = leaf.refs;
    double avg[3] = {0, 0, 0};
    for (const std::uint32_t s : leaf.refs)
        for (int a = 0; a < 3; ++a) avg[a] += nrm(splats[s], a);
    int order[3] = {0, 1, 2};
    std::sort(order, order + 3, [&](int x, int y) { return std::abs(avg[x]) > std::abs(avg[y]); });
    const std::uint32_t K = opt.shrink_slices;
    std::vector<double> bounds(K + 1);
    for (std::uint32_t k = 0; k < opt.shrink_axes; ++k) {
        const int a = order[k];
        const double lo = out.box.lo[a], hi = out.box.hi[a];
        if (!(hi > lo)) continue;
        bounds[0] = lo;
        bounds[K] = hi;
        for (std::uint32_t j = 1; j < K; ++j)
            bounds[j] = static_cast<float>(lo + (hi - lo) * double(j) / double(K));  // float planes
        auto occupied = [&](std::uint32_t j) {
            Box slice = out.box;
            slice.lo[a] = bounds[j];
            slice.hi[a] = bounds[j + 1];
            if (!(slice.hi[a] >= slice.lo[a])) return true;
            return may_contain_surface(slice, splats, out.refs, opt.shrink_depth, &out.boxes);
        };
        std::uint32_t first = K;
        for (std::uint32_t j = 0; j < K; ++j)
            if (occupied(j)) {
                first = j;
                break;
            }
        if (first == K) {  // no slice holds the surface: the whole cell is empty
            out.empty = true;
            out.refs.clear();
            out.cuts.clear();
            return out;
        }
        std::uint32_t last = first;
        for (std::uint32_t j = K - 1; j > first; --j)
            if (occupied(j)) {
                last = j;
                break;
            }
        // The kept cell reaches a quarter slice into the free slices beside it. A cut exactly at
        // the surface (a flat face whose plane a slice bound lands on, as on a synthetic cube at
        // most scales) leaves the crossing on the cell's boundary, where the renderer's float
        // sample o + d t0 lands on either side by rounding: from outside it then starts behind
        // the face (F < 0) and the ray passes through (holes over whole faces). The margin lies
        // in slices proven free, so F keeps the outside's sign at the new bound.
        const double margin = 0.25 * (hi - lo) / double(K);
        const double new_lo = first > 0 ? std::max(lo, double(round_down(bounds[first] - margin))) : lo;
        const double new_hi = last + 1 < K ? std::min(hi, double(round_up(bounds[last + 1] + margin))) : hi;
        if (new_lo > lo) out.cuts.push_back(Cut{a, true, static_cast<float>(new_lo)});
        if (new_hi < hi) out.cuts.push_back(Cut{a, false, static_cast<float>(new_hi)});
        if (new_lo > lo || new_hi < hi) {
            out.box.lo[a] = new_lo;
            out.box.hi[a] = new_hi;
            std::vector<std::uint32_t> kept;
            kept.reserve(out.refs.size());
            for (const std::uint32_t s : out.refs)
                if (support_overlaps(splats[s], out.box)) kept.push_back(s);
            out.refs = std::move(kept);
        }
    }
    return out;
}

}  // namespace

double BuildStats::mean_refs_per_leaf() const {
    const std::uint64_t filled = leaves - empty_leaves;
    return filled > 0 ? double(refs) / double(filled) : 0.0;
}

double encourage_factor(std::uint64_t n, double limit) {
    return std::min(1.0, (95.0 + 5.0 * double(n) * 21.0 / limit) / 200.0);
}

void validate(const BuildOptions& o) {
    auto fail = [](const std::string& what) { throw Error("invalid MLS build option: " + what); };
    if (!std::isfinite(o.support_factor) || !(o.support_factor > 0.0f))
        fail("support factor " + std::to_string(o.support_factor) + " must be > 0");
    if (o.samples < 2 || o.samples > 1024) fail("samples " + std::to_string(o.samples) + " outside 2..1024");
    if (!std::isfinite(o.cost_traversal) || !(o.cost_traversal > 0.0f)) fail("traversal cost must be > 0");
    if (!std::isfinite(o.cost_intersection) || !(o.cost_intersection > 0.0f))
        fail("intersection cost must be > 0");
    if (!std::isfinite(o.encourage_limit) || !(o.encourage_limit >= 1.0f))
        fail("encourage limit must be >= 1");
    if (o.shrink_slices < 2 || o.shrink_slices > 256)
        fail("shrink slices " + std::to_string(o.shrink_slices) + " outside 2..256");
    if (o.shrink_axes != 1 && o.shrink_axes != 3) fail("shrink axes must be 1 or 3");
    if (o.shrink_depth > 16) fail("shrink depth " + std::to_string(o.shrink_depth) + " above 16");
    if (o.max_depth < 1 || o.max_depth + k_max_shrink_splits > pool::k_max_mls_depth)
        fail("max depth " + std::to_string(o.max_depth) + " outside 1.." +
             std::to_string(pool::k_max_mls_depth - k_max_shrink_splits));
}

bool support_overlaps(const pool::MlsSplat& s, const Box& b) {
    double near2 = 0.0;
    for (int a = 0; a < 3; ++a) {
        const double p = pos(s, a);
        const double d = std::max({b.lo[a] - p, p - b.hi[a], 0.0});
        near2 += d * d;
    }
    const double inv = s.inv_support;
    return near2 * inv * inv < 1.0 + 1e-5;
}

bool may_contain_surface(const Box& b, std::span<const pool::MlsSplat> splats,
                         std::span<const std::uint32_t> candidates, std::uint32_t depth,
                         std::uint64_t* boxes) {
    struct Item {
        Box box;
        std::uint32_t level;
        std::size_t begin, end;  ///< its splats in `scratch`
    };
    std::vector<std::uint32_t> scratch;
    for (const std::uint32_t s : candidates)
        if (support_overlaps(splats[s], b)) scratch.push_back(s);
    std::vector<Item> stack{{b, 0, 0, scratch.size()}};
    std::uint64_t count = 0;
    bool result = false;
    while (!stack.empty()) {
        const Item it = stack.back();
        stack.pop_back();
        ++count;
        const std::span<const std::uint32_t> subset(scratch.data() + it.begin, it.end - it.begin);
        if (proven_free(it.box, splats, subset)) continue;
        if (it.level >= depth || count >= k_max_boxes_per_slice) {
            result = true;
            break;
        }
        // Halve along the longest side; each half keeps only the splats reaching it.
        int axis = 0;
        for (int a = 1; a < 3; ++a)
            if (it.box.hi[a] - it.box.lo[a] > it.box.hi[axis] - it.box.lo[axis]) axis = a;
        const double mid = 0.5 * (it.box.lo[axis] + it.box.hi[axis]);
        for (int side = 1; side >= 0; --side) {
            Item child{it.box, it.level + 1, scratch.size(), 0};
            (side == 0 ? child.box.hi : child.box.lo)[axis] = mid;
            for (std::size_t k = it.begin; k < it.end; ++k) {
                const std::uint32_t s = scratch[k];
                if (support_overlaps(splats[s], child.box)) scratch.push_back(s);
            }
            child.end = scratch.size();
            stack.push_back(child);
        }
    }
    if (boxes) *boxes += count;
    return result;
}

namespace {

/// The usable points as splats (finite position, non-zero normal, support radius R = factor x
/// radius > 0), in input order.
std::vector<pool::MlsSplat> usable_splats(std::span<const pool::Float3> positions,
                                          std::span<const pool::Float3> normals, std::span<const float> radii,
                                          const BuildOptions& opt, BuildStats& st) {
    std::vector<pool::MlsSplat> raw;
    raw.reserve(positions.size());
    for (std::size_t i = 0; i < positions.size(); ++i) {
        const pool::Float3 p = positions[i];
        const pool::Float3 n = normals[i];
        const double support = double(radii[i]) * double(opt.support_factor);
        const double nl = std::sqrt(double(n.x) * n.x + double(n.y) * n.y + double(n.z) * n.z);
        const float inv = static_cast<float>(1.0 / support);
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z) || !std::isfinite(nl) ||
            !(nl > 0.0) || !std::isfinite(support) || !(support > 0.0) || !std::isfinite(inv) ||
            !(inv > 0.0f) || i > 0xFFFFFFFFull) {
            ++st.skipped;
            continue;
        }
        raw.push_back(pool::MlsSplat{p, inv, pool::Float3{float(n.x / nl), float(n.y / nl), float(n.z / nl)},
                                     static_cast<std::uint32_t>(i)});
    }
    if (raw.empty())
        throw Error("MLS build: none of the " + std::to_string(positions.size()) +
                    " points has a finite position, a non-zero normal and a radius > 0");
    if (raw.size() > pool::k_mls_index_max) throw Error("MLS build: too many splats for the node layout");
    return raw;
}

/// The splats in Morton order into model.splats, their support boxes [p - R, p + R] in `boxes`;
/// returns the root box (float bounds, rounded outwards).
Box sort_splats(std::vector<pool::MlsSplat> raw, unsigned threads, MlsModel& model, std::vector<Box>& boxes) {
    Box root{};
    for (int a = 0; a < 3; ++a) {
        root.lo[a] = std::numeric_limits<double>::infinity();
        root.hi[a] = -std::numeric_limits<double>::infinity();
    }
    std::vector<Box> raw_boxes(raw.size());
    for (std::size_t i = 0; i < raw.size(); ++i) {
        const double r = support_radius(raw[i]);
        for (int a = 0; a < 3; ++a) {
            raw_boxes[i].lo[a] = pos(raw[i], a) - r;
            raw_boxes[i].hi[a] = pos(raw[i], a) + r;
            root.lo[a] = std::min(root.lo[a], raw_boxes[i].lo[a]);
            root.hi[a] = std::max(root.hi[a], raw_boxes[i].hi[a]);
        }
    }
    for (int a = 0; a < 3; ++a) {  // float cell bounds, rounded outwards
        root.lo[a] = round_down(root.lo[a]);
        root.hi[a] = round_up(root.hi[a]);
    }
    std::vector<std::uint64_t> codes(raw.size());
    for (std::size_t i = 0; i < raw.size(); ++i) {
        const double p[3] = {pos(raw[i], 0), pos(raw[i], 1), pos(raw[i], 2)};
        codes[i] = morton(p, root.lo, root.hi);
    }
    std::vector<std::uint32_t> order(raw.size());
    std::iota(order.begin(), order.end(), 0u);
    pre::radix_sort(codes, &order, 63, threads);  // stable: equal codes keep the input order
    model.splats.resize(raw.size());
    boxes.resize(raw.size());
    for (std::size_t i = 0; i < raw.size(); ++i) {
        model.splats[i] = raw[order[i]];
        boxes[i] = raw_boxes[order[i]];
    }
    return root;
}

/// Pass 1 (WS05 3.4, eq. 3): the SAH tree. Breadth first on the calling thread until there are
/// enough subtrees, then one subtree per task (the same tree whatever the thread count).
std::vector<BNode> sah_tree(const SahBuilder& sah, std::size_t splat_count, const Box& root,
                            const BuildOptions& opt, unsigned threads) {
    std::vector<BNode> nodes(1);
    nodes[0].box = root;
    nodes[0].refs.resize(splat_count);
    std::iota(nodes[0].refs.begin(), nodes[0].refs.end(), 0u);
    struct Pending {
        std::uint32_t index, depth;
    };
    std::vector<Pending> frontier{{0, 0}};
    const std::size_t want = threads > 1 ? 8u * threads : 1u;
    while (frontier.size() < want) {
        std::vector<Pending> next;
        bool progressed = false;
        for (const Pending& p : frontier) {
            int axis;
            float split;
            if (p.depth < opt.max_depth && sah.find_split(nodes[p.index], axis, split)) {
                sah.split_node(nodes, p.index, axis, split);
                next.push_back({nodes[p.index].child[0], p.depth + 1});
                next.push_back({nodes[p.index].child[1], p.depth + 1});
                progressed = true;
            }
        }
        if (!progressed) {
            frontier.clear();
            break;
        }
        frontier = std::move(next);
    }
    std::vector<std::vector<BNode>> local(frontier.size());
    parallel_chunks(frontier.size(), 1, threads, [&](std::size_t begin, std::size_t end, unsigned) {
        for (std::size_t f = begin; f < end; ++f) {
            local[f].resize(1);
            local[f][0].box = nodes[frontier[f].index].box;
            local[f][0].refs = std::move(nodes[frontier[f].index].refs);  // one task per node
            sah.build(local[f], frontier[f].depth);
        }
    });
    for (std::size_t f = 0; f < frontier.size(); ++f) {
        const auto offset = static_cast<std::uint32_t>(nodes.size()) - 1u;  // local index 1 -> nodes.size()
        for (std::size_t k = 0; k < local[f].size(); ++k) {
            BNode& n = local[f][k];
            if (n.axis >= 0) {
                n.child[0] += offset;
                n.child[1] += offset;
            }
        }
        nodes[frontier[f].index] = std::move(local[f][0]);
        for (std::size_t k = 1; k < local[f].size(); ++k) nodes.push_back(std::move(local[f][k]));
        local[f] = {};
    }
    return nodes;
}

/// The tree's SAH cost (WS05 eq. 3, areas relative to the root's) and its leaf count, into `st`.
void sah_statistics(const std::vector<BNode>& nodes, const Box& root, const BuildOptions& opt,
                    BuildStats& st) {
    const double sa_root = area(root);
    double cost = 0.0;
    for (const BNode& n : nodes) {
        const double rel = sa_root > 0.0 ? area(n.box) / sa_root : 1.0;
        if (n.axis >= 0)
            cost += opt.cost_traversal * rel;
        else
            cost += opt.cost_intersection * double(n.refs.size()) * rel;
        if (n.axis < 0) ++st.sah_leaves;
    }
    st.sah_cost = cost;
}

/// WS05 3.4.1 ("by inserting a new split plane"): leaf `leaf` becomes a chain of splits, each with
/// one empty child, at `cuts`, ending in the shrunk leaf holding `refs`.
void insert_cuts(std::vector<BNode>& nodes, std::uint32_t leaf, const std::vector<Cut>& cuts,
                 std::vector<std::uint32_t> refs, BuildStats& st) {
    std::uint32_t at = leaf;
    Box box = nodes[leaf].box;
    for (const Cut& c : cuts) {
        BNode empty, rest;
        empty.box = rest.box = box;
        if (c.low) {
            empty.box.hi[c.axis] = c.value;
            rest.box.lo[c.axis] = c.value;
        } else {
            rest.box.hi[c.axis] = c.value;
            empty.box.lo[c.axis] = c.value;
        }
        const auto first = static_cast<std::uint32_t>(nodes.size());
        BNode& n = nodes[at];
        n.axis = c.axis;
        n.split = c.value;
        n.refs = {};
        n.child[0] = first;
        n.child[1] = first + 1;
        box = rest.box;
        if (c.low) {
            nodes.push_back(std::move(empty));
            nodes.push_back(std::move(rest));
            at = first + 1;
        } else {
            nodes.push_back(std::move(rest));
            nodes.push_back(std::move(empty));
            at = first;
        }
        ++st.shrink_splits;
    }
    nodes[at].refs = std::move(refs);
}

/// Pass 2 (WS05 3.4.1): every non-empty leaf shrunk to the surface, leaves in parallel; a leaf the
/// surface misses loses its references.
void shrink_leaves(std::vector<BNode>& nodes, std::span<const pool::MlsSplat> splats, const BuildOptions& opt,
                   unsigned threads, const std::function<void(std::uint64_t, std::uint64_t)>& progress,
                   BuildStats& st) {
    std::vector<std::uint32_t> leaves;
    for (std::uint32_t i = 0; i < nodes.size(); ++i)
        if (nodes[i].axis < 0 && !nodes[i].refs.empty()) leaves.push_back(i);
    std::vector<ShrinkOutcome> outcomes(leaves.size());
    std::atomic<std::uint64_t> done{0};
    parallel_chunks(leaves.size(), 64, threads, [&](std::size_t begin, std::size_t end, unsigned worker) {
        for (std::size_t k = begin; k < end; ++k) outcomes[k] = shrink_leaf(nodes[leaves[k]], splats, opt);
        const std::uint64_t d = done.fetch_add(end - begin) + (end - begin);
        if (worker == 0 && progress) progress(d, leaves.size());
    });
    for (std::size_t k = 0; k < leaves.size(); ++k) {
        ShrinkOutcome& o = outcomes[k];
        st.interval_boxes += o.boxes;
        const std::uint32_t leaf = leaves[k];
        const std::size_t before = nodes[leaf].refs.size();
        if (o.empty) {
            ++st.culled_leaves;
            st.refs_removed += before;
            nodes[leaf].refs = {};
            continue;
        }
        st.refs_removed += before - o.refs.size();
        if (o.cuts.empty()) continue;
        ++st.shrunk_leaves;
        insert_cuts(nodes, leaf, o.cuts, std::move(o.refs), st);
    }
}

/// Pass 3 (WS05 3.4.3): splits whose two children are empty leaves become empty leaves (children
/// come after their parents, so decreasing indices see the children first).
void post_collapse(std::vector<BNode>& nodes, BuildStats& st) {
    for (std::size_t i = nodes.size(); i-- > 0;) {
        BNode& n = nodes[i];
        if (n.axis < 0) continue;
        const BNode& l = nodes[n.child[0]];
        const BNode& r = nodes[n.child[1]];
        if (l.axis < 0 && r.axis < 0 && l.refs.empty() && r.refs.empty()) {
            n.axis = -1;
            ++st.collapsed;
        }
    }
}

/// Pass 4: the pool's node and reference arrays, children in pairs, depth first.
void flatten(const std::vector<BNode>& nodes, MlsModel& model) {
    BuildStats& st = model.stats;
    struct Emit {
        std::uint32_t node, slot, depth;
    };
    std::vector<Emit> stack{{0, 0, 0}};
    model.nodes.resize(1);
    std::uint32_t depth = 0;
    while (!stack.empty()) {
        const Emit e = stack.back();
        stack.pop_back();
        const BNode& n = nodes[e.node];
        depth = std::max(depth, e.depth);
        if (n.axis < 0) {
            if (model.refs.size() + n.refs.size() > 0xFFFFFFFFull || n.refs.size() > pool::k_mls_index_max)
                throw Error("MLS build: more references than the pool layout holds (2^32)");
            const auto first = static_cast<std::uint32_t>(model.refs.size());
            model.refs.insert(model.refs.end(), n.refs.begin(), n.refs.end());
            model.nodes[e.slot] = pool::make_mls_leaf(first, static_cast<std::uint32_t>(n.refs.size()));
            ++st.leaves;
            if (n.refs.empty()) ++st.empty_leaves;
            continue;
        }
        const std::size_t left = model.nodes.size();
        if (left + 1 > pool::k_mls_index_max)
            throw Error("MLS build: more nodes than the pool layout holds (2^30)");
        model.nodes.resize(left + 2);
        model.nodes[e.slot] =
            pool::make_mls_inner(std::bit_cast<std::uint32_t>(n.split), static_cast<std::uint32_t>(n.axis),
                                 static_cast<std::uint32_t>(left));
        stack.push_back({n.child[1], static_cast<std::uint32_t>(left + 1), e.depth + 1});
        stack.push_back({n.child[0], static_cast<std::uint32_t>(left), e.depth + 1});
    }
    if (depth > pool::k_max_mls_depth)
        throw Error("MLS build: tree depth " + std::to_string(depth) + " exceeds " +
                    std::to_string(pool::k_max_mls_depth));
    st.nodes = model.nodes.size();
    st.refs = model.refs.size();
    st.depth = depth;
}

/// The MlsInfo record of the finished model.
void fill_info(MlsModel& model, const Box& root, const BuildOptions& opt) {
    pool::MlsInfo& info = model.info;
    for (int a = 0; a < 3; ++a) {
        info.root_lo[a] = static_cast<float>(root.lo[a]);
        info.root_hi[a] = static_cast<float>(root.hi[a]);
    }
    info.node_count = static_cast<std::uint32_t>(model.nodes.size());
    info.ref_count = static_cast<std::uint32_t>(model.refs.size());
    info.splat_count = static_cast<std::uint32_t>(model.splats.size());
    info.depth = model.stats.depth;
    info.support_factor = opt.support_factor;
    info.samples = opt.samples;
    info.flags = (opt.shrink ? pool::k_mls_shrunk : 0u) | (opt.encourage ? pool::k_mls_encouraged : 0u) |
                 (opt.collapse ? pool::k_mls_collapsed : 0u);
    info.leaf_count = static_cast<std::uint32_t>(model.stats.leaves);
}

double leaf_volume(const std::vector<BNode>& nodes) {
    double v = 0;
    for (const BNode& n : nodes)
        if (n.axis < 0 && !n.refs.empty()) v += volume(n.box);
    return v;
}

}  // namespace

MlsModel build_mls(std::span<const pool::Float3> positions, std::span<const pool::Float3> normals,
                   std::span<const float> radii, const BuildOptions& opt,
                   const std::function<void(std::uint64_t, std::uint64_t)>& progress) {
    validate(opt);
    if (normals.size() != positions.size() || radii.size() != positions.size())
        throw Error("MLS build: " + std::to_string(positions.size()) + " positions, " +
                    std::to_string(normals.size()) + " normals and " + std::to_string(radii.size()) +
                    " radii: every point needs all three");
    const double t_start = tool::now_seconds();
    const unsigned threads = resolve_threads(opt.threads);
    MlsModel model;
    BuildStats& st = model.stats;
    st.points = positions.size();

    std::vector<Box> boxes;
    const Box root = sort_splats(usable_splats(positions, normals, radii, opt, st), threads, model, boxes);
    st.splats = model.splats.size();
    const std::span<const pool::MlsSplat> splats(model.splats);

    const SahBuilder sah{splats, boxes, opt};
    std::vector<BNode> nodes = sah_tree(sah, splats.size(), root, opt, threads);  // pass 1
    sah_statistics(nodes, root, opt, st);
    st.seconds_sah = tool::now_seconds() - t_start;

    const double t_shrink = tool::now_seconds();
    st.volume_before = leaf_volume(nodes);
    if (opt.shrink) shrink_leaves(nodes, splats, opt, threads, progress, st);  // pass 2
    st.volume_after = leaf_volume(nodes);
    st.seconds_shrink = tool::now_seconds() - t_shrink;

    if (opt.collapse) post_collapse(nodes, st);  // pass 3
    flatten(nodes, model);                       // pass 4
    fill_info(model, root, opt);
    if (opt.bvh) build_mls_bvh(model);  // pass 5
    st.seconds_total = tool::now_seconds() - t_start;
    return model;
}

}  // namespace prt::mls
