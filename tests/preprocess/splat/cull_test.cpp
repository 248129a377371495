// Probe-ray culling (thesis 3.4, preprocess/splat/cull_build.h) and prt-cull.
//
// Built twice from this file: prt_cull_tests (label cpu) runs everything but the GPU comparison;
// prt_cull_gpu_tests (label gpu, PRT_CULL_GPU_TESTS=1) compares the CUDA path with the CPU path
// and skips where no CUDA device is usable.
//
// References are computed here, independently of the code under test: leaf boxes by walking the
// node pool in long double, "centre in leaf" in double, ray-disk intersections of re-shot probes
// in double with tolerances that make a float rounding difference at a rim or a leaf face count
// for the code, never against it (strict on the unculled side, lenient on the culled side). The
// probes themselves are the code's (make_probe and friends): "the same probes" is what is tested.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "cull_build.h"
#include "cull_probe_hits.h"
#include "octree_build.h"
#include "point_cloud.h"
#include "prt/formats/pool.h"
#include "runtime/tool_fixture.h"
#include "synth.h"

namespace {

namespace fs = std::filesystem;
using namespace prt;

// ---- Test models -------------------------------------------------------------------------------

/// A model as the tools see it: the point pool bytes, and its replicated octree.
struct Model {
    std::string name;
    pre::PointCloud cloud;
    pre::SplatOctree octree;
    pre::OctreeSections sections() const {
        pre::OctreeSections s;
        s.info = octree.info;
        s.nodes = octree.nodes;
        s.leaf_info = octree.leaf_info;
        s.splats = octree.splats;
        return s;
    }
};

/// prt-synth's shape with `n` points (R2 sampling: near-uniform spacing) and a constant splat
/// radius: the 9-nearest-neighbour distance of a uniform density on the surface's area,
/// sqrt(9 A / (pi n)), times 1.1 (thesis 3.1's k-NN radius, without a k-NN search).
Model make_model(const std::string& name, synth::ShapeKind kind, std::uint64_t n) {
    synth::SynthOptions o;
    o.shape.kind = kind;
    o.count = n;
    synth::SynthResult r = synth::synthesize(o);
    double area = 0;
    for (const synth::PartRange& p : r.parts) area += p.area;
    const float radius =
        static_cast<float>(1.1 * std::sqrt(9.0 * area / (3.14159265358979323846 * double(n))));
    Model m;
    m.name = name;
    m.cloud = std::move(r.cloud);
    m.cloud.radii.assign(m.cloud.size(), radius);
    // The local frame exactly as a pool stores it (float offsets from the bounding-box centre).
    pool::PoolWriter w;
    pre::write_point_sections(m.cloud, w);
    const pool::PoolFile f = pool::PoolFile::from_bytes(w.serialize(), name);
    const auto pos = f.array<pool::Float3>(pool::SectionType::positions);
    const auto nor = f.array<pool::Float3>(pool::SectionType::normals);
    const auto rad = f.array<float>(pool::SectionType::radii);
    m.octree = pre::build_octree(pos, nor, rad, pre::OctreeParams{});
    return m;
}

const Model& sphere_model() {
    static const Model m = make_model("sphere", synth::ShapeKind::sphere, 20000);
    return m;
}
const Model& room_model() {
    static const Model m = make_model("room", synth::ShapeKind::room, 40000);
    return m;
}

/// Culling on the CPU with the defaults (the reference path).
pre::CullParams cpu_params() {
    pre::CullParams p;
    p.backend = "cpu";
    return p;
}

struct Culled {
    pre::CulledOctree octree;
    pre::CullStats stats;
    pre::OctreeSections sections(const Model& m) const {
        pre::OctreeSections s;
        s.info = octree.info;
        s.nodes = m.octree.nodes;
        s.leaf_info = octree.leaf_info;
        s.splats = octree.splats;
        return s;
    }
};

const Culled& culled(const Model& m) {
    static std::map<std::string, Culled> cache;
    auto it = cache.find(m.name);
    if (it == cache.end()) {
        Culled c;
        c.octree = pre::cull_octree(m.sections(), cpu_params(), &c.stats);
        it = cache.emplace(m.name, std::move(c)).first;
    }
    return it->second;
}

// ---- Independent references ----------------------------------------------------------------------

/// A filled leaf found by walking the node pool here (Morton child order, POOL.md), with its box
/// in long double.
struct RefLeaf {
    std::uint32_t node, level;
    double lo[3], hi[3];
};

[[maybe_unused]] std::vector<RefLeaf> reference_leaves(const pre::SplatOctree& o) {
    std::vector<RefLeaf> out(o.info.filled_leaves);
    struct Item {
        std::uint32_t node, level;
        std::uint64_t cell[3];
    };
    std::vector<Item> queue{{0, 0, {0, 0, 0}}};
    for (std::size_t q = 0; q < queue.size(); ++q) {
        const Item it = queue[q];
        const std::uint32_t word = o.nodes[it.node];
        const std::uint32_t a = pool::node_address(word);
        if (pool::node_type(word) == pool::NodeType::internal) {
            for (std::uint32_t c = 0; c < 8; ++c)
                queue.push_back({a + c,
                                 it.level + 1,
                                 {2 * it.cell[0] + (c & 1), 2 * it.cell[1] + ((c >> 1) & 1),
                                  2 * it.cell[2] + ((c >> 2) & 1)}});
        } else if (pool::node_type(word) == pool::NodeType::filled_leaf) {
            RefLeaf& l = out.at(a);
            l.node = word;
            l.level = it.level;
            const long double s =
                static_cast<long double>(o.info.root_size) / static_cast<long double>(1ull << it.level);
            for (int k = 0; k < 3; ++k) {
                l.lo[k] = double(static_cast<long double>(o.info.root_min[k]) + s * it.cell[k]);
                l.hi[k] = double(static_cast<long double>(o.info.root_min[k]) + s * (it.cell[k] + 1));
            }
        }
    }
    return out;
}

[[maybe_unused]] bool centre_in(const pool::Splat& s, const RefLeaf& l) {
    const double c[3] = {s.position.x, s.position.y, s.position.z};
    for (int k = 0; k < 3; ++k)
        if (!(c[k] >= l.lo[k] && c[k] <= l.hi[k])) return false;
    return true;
}

/// Ray-disk intersection in double: the ray parameter t and the distance from the centre over the
/// radius, and the side: 0 when the disk faces against d (d.n < 0), 1 when it faces along d.
struct RefHit {
    double t, x_over_r;
    int side;
};
[[maybe_unused]] bool ref_intersect(const pool::Splat& s, const double o[3], const double d[3], RefHit& h) {
    const double n[3] = {s.normal.x, s.normal.y, s.normal.z};
    const double c[3] = {s.position.x, s.position.y, s.position.z};
    const double dn = d[0] * n[0] + d[1] * n[1] + d[2] * n[2];
    if (std::fabs(dn) < 1e-3) return false;  // grazing: t is ill-conditioned, no reference call
    h.t = ((c[0] - o[0]) * n[0] + (c[1] - o[1]) * n[1] + (c[2] - o[2]) * n[2]) / dn;
    double x2 = 0;
    for (int k = 0; k < 3; ++k) {
        const double p = o[k] + h.t * d[k] - c[k];
        x2 += p * p;
    }
    h.x_over_r = std::sqrt(x2) / double(s.radius);
    h.side = dn > 0 ? 1 : 0;
    return true;
}

/// The parameter range of the line o + t d inside a box (double slab test); false when it misses.
[[maybe_unused]] bool ref_box_range(const RefLeaf& l, const double o[3], const double d[3], double& t0,
                                    double& t1) {
    t0 = -1e300;
    t1 = 1e300;
    for (int k = 0; k < 3; ++k) {
        if (d[k] == 0) {
            if (o[k] < l.lo[k] || o[k] > l.hi[k]) return false;
            continue;
        }
        const double a = (l.lo[k] - o[k]) / d[k], b = (l.hi[k] - o[k]) / d[k];
        t0 = std::max(t0, std::min(a, b));
        t1 = std::min(t1, std::max(a, b));
    }
    return t0 <= t1;
}

// ---- Tests ---------------------------------------------------------------------------------------

#if !PRT_CULL_GPU_TESTS

class CullModels : public ::testing::TestWithParam<const char*> {
protected:
    const Model& model() const { return std::string(GetParam()) == "sphere" ? sphere_model() : room_model(); }
};

TEST_P(CullModels, CentreSplatsAreNeverRemovedAndNothingIsAdded) {
    const Model& m = model();
    const Culled& c = culled(m);
    const std::vector<RefLeaf> leaves = reference_leaves(m.octree);
    ASSERT_EQ(c.octree.leaf_info.size(), m.octree.leaf_info.size());
    std::uint64_t centres = 0;
    for (std::size_t a = 0; a < leaves.size(); ++a) {
        std::multiset<std::uint32_t> before_centres, before_all, after;
        for (std::uint32_t i = m.octree.leaf_info[a]; i < m.octree.leaf_info[a + 1]; ++i) {
            before_all.insert(m.octree.splats[i].point);
            if (centre_in(m.octree.splats[i], leaves[a])) before_centres.insert(m.octree.splats[i].point);
        }
        for (std::uint32_t i = c.octree.leaf_info[a]; i < c.octree.leaf_info[a + 1]; ++i)
            after.insert(c.octree.splats[i].point);
        centres += before_centres.size();
        EXPECT_TRUE(std::includes(after.begin(), after.end(), before_centres.begin(), before_centres.end()))
            << m.name << ": leaf " << a << " lost a splat whose centre it holds";
        EXPECT_TRUE(std::includes(before_all.begin(), before_all.end(), after.begin(), after.end()))
            << m.name << ": leaf " << a << " gained a splat";
    }
    EXPECT_EQ(centres, c.stats.centre_splats);
    // Every point still has its splat in the leaf holding its centre.
    EXPECT_GE(centres, m.cloud.size());
}

TEST_P(CullModels, EveryProbeStillSeesTheSameSurface) {
    // Re-shoot the culling's own probes (the defaults) at the culled octree: a probe ray that hit
    // a splat of the unculled leaf must hit a kept splat of the culled leaf, from the same side,
    // no farther than the blending window behind the unculled leaf's nearest hit (closer is
    // impossible: the culled leaf's splats are a subset).
    const Model& m = model();
    const Culled& c = culled(m);
    const pre::CullParams params = cpu_params();
    const std::vector<pre::CullLeaf> leaves = pre::collect_leaves(m.sections());
    const std::vector<RefLeaf> ref = reference_leaves(m.octree);
    const std::vector<core::ProbeDirection> dirs =
        pre::make_probe_directions(params.directions, 64, params.seed);
    core::CullView view;
    view.octree = pre::octree_view(m.sections());
    view.leaves = leaves.data();
    view.directions = dirs.data();
    view.direction_sets = 64;
    view.directions_per_set = params.directions;
    view.grid = params.grid;
    view.window = params.window;
    view.seed = params.seed;
    const std::uint32_t lines = core::probes_per_leaf(view), per_dir = params.grid * params.grid;
    std::uint64_t probes = 0, hit = 0, failures = 0;
    for (std::uint32_t a = 0; a < leaves.size(); ++a) {
        core::ProbeRegion region;
        if (!core::probe_region(view, a, region)) continue;
        const double edge = ref[a].hi[0] - ref[a].lo[0];
        const double delta = 1e-4 * edge;  // leaf-face tolerance
        core::ProbeFrame frame{};
        for (std::uint32_t k = 0; k < lines; ++k) {
            if (k % per_dir == 0) core::probe_frame(view, a, region, k / per_dir, frame);
            core::Vec3 of, df;
            float t_max, t0, t1;
            if (!core::make_probe(view, a, region, frame, k, of, df, t_max)) continue;
            if (!core::probe_leaf_range(view, a, of, df, t_max, t0, t1)) continue;
            ++probes;
            const double o[3] = {of.x, of.y, of.z}, d[3] = {df.x, df.y, df.z};
            double b0, b1;
            if (!ref_box_range(ref[a], o, d, b0, b1)) continue;
            const double strict_lo = std::max<double>(t0, b0) + delta,
                         strict_hi = std::min<double>(t1, b1) - delta;
            const double loose_lo = std::min<double>(t0, b0) - delta,
                         loose_hi = std::max<double>(t1, b1) + delta;
            for (int side = 0; side < 2; ++side) {
                // nearest strict hit of the unculled leaf, distance s along this side's ray
                double near_s = 1e300, near_r = 0;
                for (std::uint32_t i = m.octree.leaf_info[a]; i < m.octree.leaf_info[a + 1]; ++i) {
                    RefHit h;
                    if (!ref_intersect(m.octree.splats[i], o, d, h) || h.side != side) continue;
                    if (!(h.x_over_r <= 1.0 - 1e-3 && h.t >= strict_lo && h.t <= strict_hi)) continue;
                    const double s = side ? -h.t : h.t;
                    if (s < near_s) {
                        near_s = s;
                        near_r = m.octree.splats[i].radius;
                    }
                }
                if (near_s == 1e300) continue;
                ++hit;
                const double limit = near_s + double(params.window) * near_r + delta;
                bool served = false;
                for (std::uint32_t i = c.octree.leaf_info[a]; i < c.octree.leaf_info[a + 1] && !served; ++i) {
                    RefHit h;
                    if (!ref_intersect(c.octree.splats[i], o, d, h) || h.side != side) continue;
                    const double s = side ? -h.t : h.t;
                    served = h.x_over_r <= 1.0 + 1e-3 && h.t >= loose_lo && h.t <= loose_hi && s <= limit;
                }
                if (!served && ++failures <= 5)
                    ADD_FAILURE() << m.name << ": leaf " << a << " probe " << k << " side " << side
                                  << " hit the unculled leaf at s = " << near_s
                                  << " but no kept splat within " << limit;
            }
        }
    }
    EXPECT_EQ(failures, 0u) << "of " << hit << " probe rays that hit";
    EXPECT_GT(probes, 1000u);
    EXPECT_GT(hit, probes / 10) << "probes aimed at the surface mostly miss it";
    std::printf("%s: %llu probe lines re-shot, %llu probe rays hit the unculled leaf, %llu not served\n",
                m.name.c_str(), (unsigned long long)probes, (unsigned long long)hit,
                (unsigned long long)failures);
}

TEST_P(CullModels, ReplicationDropsAndHoleRateStaysBelowTheBound) {
    const Model& m = model();
    const Culled& c = culled(m);
    const pre::CullStats& s = c.stats;
    EXPECT_EQ(s.splats_before, m.octree.splats.size());
    EXPECT_EQ(s.splats_after, c.octree.splats.size());
    EXPECT_EQ(s.splats_after, s.centre_splats + s.replicas_kept);
    EXPECT_EQ(c.octree.info.splat_count, c.octree.splats.size());
    EXPECT_EQ(c.octree.info.flags, m.octree.info.flags | pool::k_octree_culled);
    EXPECT_GT(s.replication_before(), 2.0) << "the test model should replicate";
    EXPECT_LE(s.replication_after(), 1.5);  // the goal
    EXPECT_LT(s.replication_after(), s.replication_before());
    pre::HoleParams hp;
    hp.rays = 200000;
    hp.backend = "cpu";
    const pre::HoleStats h = pre::measure_holes(m.sections(), c.sections(m), hp);
    EXPECT_EQ(h.total.rays, hp.rays);
    EXPECT_GT(h.total.hit_full, hp.rays / 5);
    EXPECT_EQ(h.total.spurious, 0u) << "the culled splats are a subset: nothing can appear";
    EXPECT_LT(h.total.hole_rate(), 0.001);  // the bound: 0.1 %
    std::printf(
        "%s: %llu points, splats %llu -> %llu (replication %.3f -> %.3f), hole rate %.4f %% "
        "(%llu of %llu), mean normal change %.3f deg\n",
        m.name.c_str(), (unsigned long long)m.cloud.size(), (unsigned long long)s.splats_before,
        (unsigned long long)s.splats_after, s.replication_before(), s.replication_after(),
        100.0 * h.total.hole_rate(), (unsigned long long)h.total.holes(),
        (unsigned long long)h.total.hit_full, h.total.mean_normal_error());
}

INSTANTIATE_TEST_SUITE_P(Models, CullModels, ::testing::Values("sphere", "room"),
                         [](const ::testing::TestParamInfo<const char*>& i) { return std::string(i.param); });

TEST(Cull, HoleOutcomeLeavesRaysStartingOnTheSurfaceUncounted) {
    using pre::HoleOutcome;
    const double tol = 3.0e-3;  // 3 mean radii of 1e-3
    auto sample = [](bool hit_full, float t_full, bool hit_culled, float t_culled) {
        pre::HoleSample s{};
        s.hit_full = hit_full;
        s.t_full = t_full;
        s.hit_culled = hit_culled;
        s.t_culled = t_culled;
        return s;
    };
    EXPECT_EQ(pre::classify_hole_sample(sample(false, 0, false, 0), tol), HoleOutcome::no_hit);
    EXPECT_EQ(pre::classify_hole_sample(sample(false, 0, true, 1.0f), tol), HoleOutcome::spurious);
    // The Stanford bunny's case: a camera 8e-6 from a disk (0.01 radii); the culled octree misses.
    EXPECT_EQ(pre::classify_hole_sample(sample(true, 8e-6f, false, 0), tol), HoleOutcome::on_surface);
    EXPECT_EQ(pre::classify_hole_sample(sample(true, 2.9e-3f, true, 0.5f), tol), HoleOutcome::on_surface);
    // From the tolerance on, misses and far hits are holes, near hits are not.
    EXPECT_EQ(pre::classify_hole_sample(sample(true, 3.1e-3f, false, 0), tol), HoleOutcome::missed);
    EXPECT_EQ(pre::classify_hole_sample(sample(true, 0.5f, false, 0), tol), HoleOutcome::missed);
    EXPECT_EQ(pre::classify_hole_sample(sample(true, 0.5f, true, 0.504f), tol), HoleOutcome::wrong_surface);
    EXPECT_EQ(pre::classify_hole_sample(sample(true, 0.5f, true, 0.496f), tol), HoleOutcome::wrong_surface);
    EXPECT_EQ(pre::classify_hole_sample(sample(true, 0.5f, true, 0.502f), tol), HoleOutcome::same);
    // A non-finite unculled hit is not hidden as "on the surface".
    EXPECT_NE(pre::classify_hole_sample(sample(true, std::nanf(""), false, 0), tol), HoleOutcome::on_surface);
}

TEST(Cull, HoleMeasurementSeesHolesAndNoneWithoutCulling) {
    const Model& m = sphere_model();
    pre::HoleParams hp;
    hp.rays = 50000;
    hp.backend = "cpu";
    // Against itself: no holes, identical hits.
    const pre::HoleStats same = pre::measure_holes(m.sections(), m.sections(), hp);
    EXPECT_EQ(same.total.holes(), 0u);
    EXPECT_GT(same.total.hit_full, 0u);
    EXPECT_NEAR(same.total.mean_normal_error(), 0.0, 0.05);  // acos of a float dot product near 1
    // Centre splats only (every replica removed, as without replication): many holes.
    pre::CulledOctree centres;
    centres.info = m.octree.info;
    const std::vector<RefLeaf> ref = reference_leaves(m.octree);
    for (std::size_t a = 0; a < ref.size(); ++a) {
        centres.leaf_info.push_back(static_cast<std::uint32_t>(centres.splats.size()));
        for (std::uint32_t i = m.octree.leaf_info[a]; i < m.octree.leaf_info[a + 1]; ++i)
            if (centre_in(m.octree.splats[i], ref[a])) centres.splats.push_back(m.octree.splats[i]);
    }
    centres.leaf_info.push_back(static_cast<std::uint32_t>(centres.splats.size()));
    centres.info.splat_count = centres.splats.size();
    pre::OctreeSections cs = m.sections();
    cs.info = centres.info;
    cs.leaf_info = centres.leaf_info;
    cs.splats = centres.splats;
    const pre::HoleStats holes = pre::measure_holes(m.sections(), cs, hp);
    EXPECT_GT(holes.total.hole_rate(), 0.01)
        << "without replicas, rays fall through leaf borders (thesis 3.4)";
    EXPECT_EQ(holes.total.spurious, 0u);
    // Mismatched octrees are refused.
    pre::OctreeSections other = m.sections();
    other.info.root_size *= 2;
    EXPECT_THROW(pre::measure_holes(m.sections(), other, hp), Error);
}

// The CPU backend's four-wide probe-hit pass must give what cull.h's scalar probe_hits (the CUDA
// backend's) gives, bit for bit, or the backends keep different replicas: random disks with the
// cases that decide a test at its edge (normals across the line, zero radii, NaN coordinates,
// coincident disks whose tie the first one wins, lines along an axis with axis-aligned normals),
// every keep flag, leaves of 1 to 13 splats (padding lanes) through one pass object (its per-leaf
// copy), lines with empty ranges, a zero-radius disk whose centre a line meets exactly, and lines
// from a disk's plane (hits at t = +0 and -0).
TEST(CullProbeHits, SameHitsAsTheScalarPass) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    const auto unit = [&] {
        core::Vec3 n{u(rng), u(rng), u(rng)};
        return core::normalize_or(n, core::Vec3{0.0f, 0.0f, 1.0f});
    };
    const auto bits = [](float x) {
        std::uint32_t b;
        std::memcpy(&b, &x, 4);
        return b;
    };
    std::size_t lines = 0, hit_sides = 0, zero_sides = 0;
    std::vector<std::vector<pool::Splat>> leaves(400);  // alive throughout: one pass object for all
    pre::LeafProbeHits soa;
    for (int trial = 0; trial < 400; ++trial) {
        const std::uint32_t count = 1 + static_cast<std::uint32_t>(trial % 13);
        const std::uint32_t pad = static_cast<std::uint32_t>(trial % 3);  // the leaf's place in the array
        std::vector<pool::Splat>& splats = leaves[static_cast<std::size_t>(trial)];
        splats.resize(pad + count + 2);
        std::vector<std::uint8_t> keep(splats.size());
        for (std::size_t i = 0; i < splats.size(); ++i) {
            pool::Splat& s = splats[i];
            const core::Vec3 p{u(rng) * 0.5f, u(rng) * 0.5f, u(rng) * 0.5f};
            core::Vec3 n = unit();
            const int edge = static_cast<int>(rng() % 10);
            if (edge == 0) n = core::Vec3{0.0f, 0.0f, (rng() & 1u) ? 1.0f : -1.0f};  // across z lines
            if (edge == 1) n = core::Vec3{0.0f, 0.0f, 0.0f};
            if (edge == 7) n = core::Vec3{1.0f, 0.0f, 0.0f};  // along z lines: d.n = 0
            s.position = {p.x, p.y, p.z};
            s.normal = {n.x, n.y, n.z};
            s.radius = edge == 2 ? 0.0f : 0.2f + 0.6f * std::fabs(u(rng));
            if (edge == 3) s.position.y = std::numeric_limits<float>::quiet_NaN();
            if (edge >= 4 && edge <= 6 && i > 0) {  // a coincident disk of another radius: a tie
                const float r = s.radius;
                s = splats[i - 1];
                s.radius = r;
            }
            s.point = static_cast<std::uint32_t>(i);
            keep[i] = static_cast<std::uint8_t>(rng() % 3);
        }
        pool::Splat& point = splats[pad];  // a zero-radius disk facing z lines
        point.normal = {0.0f, 0.0f, (trial & 1) ? 1.0f : -1.0f};
        point.radius = 0.0f;
        point.position.y = 0.1f;
        const pool::Splat& flat = splats[pad + count - 1];
        core::OctreeView view;
        view.splats = splats.data();
        view.splat_count = static_cast<std::uint32_t>(splats.size());
        for (int k = 0; k < 64; ++k, ++lines) {
            core::Vec3 o{u(rng) * 0.3f, u(rng) * 0.3f, -2.0f + u(rng) * 0.1f};
            core::Vec3 d = k % 4 == 0 ? core::Vec3{0.0f, 0.0f, 1.0f} : unit();
            float t0 = k % 7 == 0 ? 3.0f : std::fabs(u(rng)), t1 = 1.0f + 3.0f * std::fabs(u(rng));
            if (k == 1 && count > 1) {  // through the zero-radius disk's centre: x^2 = r^2 = 0
                o = core::Vec3{point.position.x, point.position.y, -2.0f};
                d = core::Vec3{0.0f, 0.0f, 1.0f};
                t0 = 0.0f;
            }
            if (k == 2 || k == 3) {  // from a point of the last disk's plane: t = +0 or -0
                o = core::Vec3{flat.position.x, flat.position.y, flat.position.z};
                t0 = 0.0f;
            }
            core::cull_detail::SideHits want[2], got[2];
            core::CullCounters cw, cg;
            core::cull_detail::probe_hits(view, pad, pad + count, keep.data(), core::k_keep_centre, o, d, t0,
                                          t1, want, cw);
            soa(view, pad, pad + count, keep.data(), o, d, t0, t1, got, cg);
            ASSERT_EQ(cw.splat_tests, cg.splat_tests);
            for (int side = 0; side < 2; ++side) {
                SCOPED_TRACE("trial " + std::to_string(trial) + " line " + std::to_string(k) + " side " +
                             std::to_string(side));
                ASSERT_EQ(bits(want[side].near_s), bits(got[side].near_s));
                ASSERT_EQ(bits(want[side].near_r), bits(got[side].near_r));
                ASSERT_EQ(bits(want[side].kept_s), bits(got[side].kept_s));
                ASSERT_EQ(want[side].centre, got[side].centre);
                hit_sides += want[side].near_s < core::k_inf;
                zero_sides += want[side].near_s == 0.0f;
            }
            if (k == 40) keep[pad] = core::k_keep_probe;  // cull_leaf keeps a replica mid-leaf
        }
    }
    EXPECT_GT(hit_sides, lines / 8);  // the lines do meet disks (3569 of 25600 lines x 2 sides)
    EXPECT_GT(zero_sides, 100u);      // hits at t = 0 (423)
}

TEST(Cull, DeterministicAndIndependentOfThreads) {
    const Model& m = sphere_model();
    pre::CullParams a = cpu_params(), b = cpu_params();
    a.threads = 1;
    b.threads = 3;
    EXPECT_EQ(pre::cull_keep_flags(m.sections(), a), pre::cull_keep_flags(m.sections(), b));
    b.seed = 2;  // other probes: other choices, same quality class
    const auto other = pre::cull_keep_flags(m.sections(), b);
    EXPECT_NE(pre::cull_keep_flags(m.sections(), a), other);
}

TEST(Cull, PoliciesAndProbeCounts) {
    // More probes keep at least about as many replicas and never more holes than far fewer; the
    // thesis policy keeps more than greedy at the same probes.
    const Model& m = sphere_model();
    pre::CullParams few = cpu_params(), thesis = cpu_params(), votes = cpu_params();
    few.directions = 1;
    few.grid = 2;
    thesis.policy = pre::CullPolicy::thesis;
    votes.policy = pre::CullPolicy::votes;
    pre::CullStats s_few, s_thesis, s_votes;
    pre::cull_keep_flags(m.sections(), few, &s_few);
    pre::cull_keep_flags(m.sections(), thesis, &s_thesis);
    pre::cull_keep_flags(m.sections(), votes, &s_votes);
    const pre::CullStats& s_def = culled(m).stats;
    EXPECT_LT(s_few.splats_after, s_def.splats_after);
    EXPECT_GT(s_thesis.splats_after, s_def.splats_after);
    EXPECT_LT(s_votes.splats_after, s_thesis.splats_after);
    // D x G^2 lines per leaf: 1 x 2^2 against the default 4 x 8^2 (lines missing P are no probes)
    EXPECT_NEAR(double(s_def.counters.probes) / double(s_few.counters.probes), 64.0, 16.0);
}

TEST(Cull, RefusesWhatItCannotCull) {
    const Model& m = sphere_model();
    pre::OctreeSections s = m.sections();
    s.info.flags &= ~pool::k_octree_replicated;
    EXPECT_THROW(pre::cull_octree(s, cpu_params()), Error);
    pre::CullParams p = cpu_params();
    p.grid = 0;
    EXPECT_THROW(pre::cull_octree(m.sections(), p), Error);
    p = cpu_params();
    p.backend = "vulkan";
    EXPECT_THROW(pre::cull_octree(m.sections(), p), Error);
    s = m.sections();
    s.leaf_info = s.leaf_info.subspan(1);
    EXPECT_THROW(pre::cull_octree(s, cpu_params()), Error);
}

// ---- The tool ------------------------------------------------------------------------------------

class CullTool : public prt::test::ToolTest {
protected:
    CullTool() : ToolTest("prt-cull", "prt_cull_test_") {}

    /// Writes the sphere model's point sections and (optionally) its octree as a pool.
    void write_model(const std::string& name, bool octree) {
        const Model& m = sphere_model();
        pool::PoolWriter w;
        pre::write_point_sections(m.cloud, w);
        if (octree) pre::add_octree_sections(m.octree, w);
        w.add_provenance("cull_test", "0", "{}");
        w.write(path(name));
    }
};

TEST_F(CullTool, HelpDocumentsEveryOptionWithItsDefault) {
    ASSERT_EQ(run("--help"), 0);
    for (const char* o : {"--output", "--directions", "--grid", "--policy", "--window", "--seed", "--backend",
                          "--threads", "--measure-holes", "--hole-seed", "--stats-json", "--quiet"})
        EXPECT_NE(m_stdout.find(o), std::string::npos) << o;
    EXPECT_NE(m_stdout.find("--directions UINT:UINT in [1 - 256]=4"), std::string::npos) << m_stdout;
    EXPECT_NE(m_stdout.find("--grid UINT:UINT in [1 - 64]=8"), std::string::npos) << m_stdout;
    EXPECT_NE(m_stdout.find("=greedy"), std::string::npos);
    EXPECT_NE(m_stdout.find("=auto"), std::string::npos);
}

TEST_F(CullTool, WritesAValidCulledPoolCarryingTheRestOver) {
    write_model("in.pool", true);
    ASSERT_EQ(run(path("in.pool") + " -o " + path("out.pool") +
                  " --backend cpu --measure-holes 20000 --stats-json " + path("stats.json")),
              0)
        << m_stderr;
    EXPECT_NE(m_stderr.find("hole rate"), std::string::npos) << m_stderr;
    const pool::PoolFile in = pool::PoolFile::open(path("in.pool"));
    const pool::PoolFile out = pool::PoolFile::open(path("out.pool"));  // validates everything
    // carried over byte for byte: points and the node pool
    for (pool::SectionType t :
         {pool::SectionType::model_info, pool::SectionType::positions, pool::SectionType::normals,
          pool::SectionType::radii, pool::SectionType::octree_nodes}) {
        ASSERT_TRUE(out.has(t)) << pool::section_name(t);
        const auto a = in.bytes(*in.find(t)), b = out.bytes(*out.find(t));
        EXPECT_TRUE(a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin()))
            << pool::section_name(t);
    }
    const pool::OctreeInfo oi = out.array<pool::OctreeInfo>(pool::SectionType::octree_info)[0];
    const pool::OctreeInfo ii = in.array<pool::OctreeInfo>(pool::SectionType::octree_info)[0];
    EXPECT_EQ(oi.flags, ii.flags | pool::k_octree_culled);
    EXPECT_EQ(oi.node_count, ii.node_count);
    EXPECT_EQ(oi.unique_splats, ii.unique_splats);
    EXPECT_LT(oi.splat_count, ii.splat_count);
    // the same splats as the library's culling with the same parameters
    const Culled& c = culled(sphere_model());
    const auto splats = out.array<pool::Splat>(pool::SectionType::splats);
    ASSERT_EQ(splats.size(), c.octree.splats.size());
    EXPECT_EQ(0, std::memcmp(splats.data(), c.octree.splats.data(), splats.size_bytes()));
    const auto li = out.array<std::uint32_t>(pool::SectionType::leaf_info);
    EXPECT_TRUE(std::equal(li.begin(), li.end(), c.octree.leaf_info.begin(), c.octree.leaf_info.end()));
    // provenance: the input's entries, then prt-cull with its parameters
    const nlohmann::json prov = nlohmann::json::parse(out.provenance_json());
    ASSERT_GE(prov.size(), 2u);
    EXPECT_EQ(prov.back()["tool"], "prt-cull");
    const nlohmann::json& params = prov.back()["parameters"];
    EXPECT_EQ(params["directions"], 4);
    EXPECT_EQ(params["grid"], 8);
    EXPECT_EQ(params["policy"], "greedy");
    // statistics
    const nlohmann::json st = nlohmann::json::parse(std::ifstream(path("stats.json")));
    EXPECT_EQ(st["splats_after"], oi.splat_count);
    EXPECT_EQ(st["holes"]["total"]["rays"], 20000);
    EXPECT_LT(st["holes"]["total"]["hole_rate"].get<double>(), 0.001);
    // culling the culled pool again is allowed and keeps the centre splats
    ASSERT_EQ(run(path("out.pool") + " -o " + path("out2.pool") + " --backend cpu -q"), 0) << m_stderr;
    EXPECT_TRUE(m_stderr.empty()) << "--quiet: " << m_stderr;
    EXPECT_LE(pool::PoolFile::open(path("out2.pool")).array<pool::Splat>(pool::SectionType::splats).size(),
              splats.size());
}

TEST_F(CullTool, FailsCleanly) {
    write_model("points.pool", false);
    EXPECT_EQ(run(path("points.pool") + " -o " + path("x.pool") + " --backend cpu"), 1);
    prt::test::expect_one_line(m_stderr, {"prt-cull: error: ", "points.pool", "prt-octree"});
    EXPECT_FALSE(fs::exists(path("x.pool")));
    EXPECT_EQ(run(path("missing.pool") + " -o " + path("x.pool")), 1);
    EXPECT_EQ(run(path("points.pool") + " -o " + path("x.pool") + " --grid 0"), 2);
    EXPECT_EQ(run(path("points.pool") + " -o " + path("x.pool") + " --policy best"), 2);
    EXPECT_EQ(run(path("points.pool") + " -o " + path("x.pool") + " --backend opencl"), 2);
    // a damaged pool: one line naming the file, no output
    write_model("in.pool", true);
    {
        std::fstream f(path("in.pool"), std::ios::in | std::ios::out | std::ios::binary);
        f.seekp(-100, std::ios::end);
        f.put('\x55');
    }
    EXPECT_EQ(run(path("in.pool") + " -o " + path("x.pool") + " --backend cpu"), 1);
    EXPECT_NE(m_stderr.find("in.pool"), std::string::npos) << m_stderr;
    EXPECT_FALSE(fs::exists(path("x.pool")));
}

TEST_F(CullTool, CudaBackendWithoutADeviceSaysSo) {
    std::string why;
    if (pre::resolve_cull_backend("auto", &why) == "cuda") GTEST_SKIP() << "a CUDA device is present";
    write_model("in.pool", true);
    EXPECT_EQ(run(path("in.pool") + " -o " + path("x.pool") + " --backend cuda"), 1);
    EXPECT_NE(m_stderr.find("--backend cuda"), std::string::npos) << m_stderr;
    EXPECT_NE(m_stderr.find("--backend cpu"), std::string::npos) << m_stderr;
    // auto falls back to the CPU and says so
    EXPECT_EQ(run(path("in.pool") + " -o " + path("x.pool") + " --backend auto"), 0) << m_stderr;
    EXPECT_NE(m_stderr.find("using the CPU"), std::string::npos) << m_stderr;
}

#else  // PRT_CULL_GPU_TESTS

TEST(CullGpu, SameKeptSplatsAndHolesAsTheCpu) {
    std::string why;
    try {
        pre::resolve_cull_backend("cuda");
    } catch (const Error& e) {
        GTEST_SKIP() << e.what();
    }
    for (const Model* m : {&sphere_model(), &room_model()}) {
        for (pre::CullPolicy policy :
             {pre::CullPolicy::greedy, pre::CullPolicy::votes, pre::CullPolicy::thesis}) {
            pre::CullParams cpu = cpu_params(), gpu = cpu_params();
            cpu.policy = gpu.policy = policy;
            gpu.backend = "cuda";
            pre::CullStats sc, sg;
            const std::vector<std::uint8_t> kc = pre::cull_keep_flags(m->sections(), cpu, &sc);
            const std::vector<std::uint8_t> kg = pre::cull_keep_flags(m->sections(), gpu, &sg);
            ASSERT_EQ(kc.size(), kg.size());
            std::size_t diff = 0;
            for (std::size_t i = 0; i < kc.size(); ++i) diff += kc[i] != kg[i];
            // Same functions, same probes, no FMA contraction and IEEE division on the GPU: the
            // flags are expected to be identical; a rim-exact hit may flip (stated: <= 0.01 %).
            EXPECT_LE(diff, kc.size() / 10000) << m->name << " policy " << int(policy);
            EXPECT_NEAR(double(sg.counters.probes), double(sc.counters.probes), 1e-4 * sc.counters.probes);
            std::printf("%s policy %d: %zu of %zu keep flags differ; cpu %.3f s, gpu %.3f s (%s)\n",
                        m->name.c_str(), int(policy), diff, kc.size(), sc.seconds, sg.seconds,
                        sg.backend.c_str());
        }
        const Culled& c = culled(*m);
        pre::HoleParams hc, hg;
        hc.rays = hg.rays = 200000;
        hc.backend = "cpu";
        hg.backend = "cuda";
        const pre::HoleStats a = pre::measure_holes(m->sections(), c.sections(*m), hc);
        const pre::HoleStats b = pre::measure_holes(m->sections(), c.sections(*m), hg);
        EXPECT_NEAR(double(b.total.hit_full), double(a.total.hit_full), 1e-4 * a.total.hit_full);
        EXPECT_NEAR(double(b.total.holes()), double(a.total.holes()), 2.0 + 0.01 * a.total.holes());
        EXPECT_EQ(b.total.spurious, 0u);
    }
}

class CullGpuTool : public prt::test::ToolTest {
protected:
    CullGpuTool() : ToolTest("prt-cull", "prt_cull_gpu_test_") {}
};

// prt-cull on the GPU releases the device (its context goes on a thread while the pool is written,
// after the hole measurement's GPU rays): the pool is whole and holds the library's CUDA culling.
TEST_F(CullGpuTool, WritesTheLibrarysCudaCullingAfterReleasingTheDevice) {
    try {
        pre::resolve_cull_backend("cuda");
    } catch (const Error& e) {
        GTEST_SKIP() << e.what();
    }
    const Model& m = sphere_model();
    pool::PoolWriter w;
    pre::write_point_sections(m.cloud, w);
    pre::add_octree_sections(m.octree, w);
    w.add_provenance("cull_test", "0", "{}");
    w.write(path("in.pool"));
    ASSERT_EQ(run(path("in.pool") + " -o " + path("out.pool") + " --backend cuda --measure-holes 20000 " +
                  "--stats-json " + path("stats.json")),
              0)
        << m_stderr;
    const pool::PoolFile out = pool::PoolFile::open(path("out.pool"));  // validates everything
    pre::CullParams gpu;
    gpu.backend = "cuda";
    const pre::CulledOctree c = pre::cull_octree(m.sections(), gpu);
    const auto splats = out.array<pool::Splat>(pool::SectionType::splats);
    ASSERT_EQ(splats.size(), c.splats.size());
    EXPECT_EQ(0, std::memcmp(splats.data(), c.splats.data(), splats.size_bytes()));
    const nlohmann::json st = nlohmann::json::parse(std::ifstream(path("stats.json")));
    EXPECT_EQ(st["device"].get<std::string>().rfind("cuda", 0), 0u) << st["device"];
    EXPECT_EQ(st["holes"]["device"].get<std::string>().rfind("cuda", 0), 0u) << st["holes"]["device"];
    EXPECT_EQ(st["holes"]["total"]["rays"], 20000);
    EXPECT_LT(st["holes"]["total"]["hole_rate"].get<double>(), 0.001);
}

#endif

}  // namespace
