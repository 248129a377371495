// PointRT runtime (host): the ISO, MLS and patch sections of a pool, validated by formats
// (prt/formats/*_sections.h), turned into the core's views.
#include "prt/runtime/surface_pools.h"

#include <algorithm>

namespace prt::rt {

core::IsoView load_iso_view(const pool::PoolFile& pool, bool prefer_q8) {
    const pool::IsoSections s = pool::validate_iso(pool);
    return core::make_iso_view(s.info, s.nodes.data(), s.leaves_q8.data(), s.leaves_f32.data(), prefer_q8);
}

core::MlsView load_mls_view(const pool::PoolFile& pool) {
    const pool::MlsSections s = pool::validate_mls(pool);
    core::MlsView v = core::make_mls_view(s.info, s.nodes.data(), s.refs.data(), s.splats.data());
    core::attach_mls_bvh(v, s.bvh_nodes.data(), s.bvh_leaves.data(),
                         static_cast<std::uint32_t>(s.bvh_nodes.size()),
                         static_cast<std::uint32_t>(s.bvh_leaves.size()), s.info.bvh_depth);
    return v;
}

core::PatchView load_patch_view(const pool::PoolFile& pool) {
    const pool::PatchSections s = pool::validate_patches(pool);
    core::PatchView view;
    view.nets = s.nets.data();
    view.bvh = s.bvh.data();
    view.nodes = s.boxes.data();
    view.patch_count = s.info.patch_count;
    view.bvh_node_count = s.info.bvh_node_count;
    view.subpatch_depth = s.info.subpatch_depth;
    view.subpatch_nodes = s.info.subpatch_nodes;
    view.flags = s.info.flags;
    double extent = 0.0;
    for (int a = 0; a < 3; ++a)
        extent = std::max(extent, double(s.info.bounds_max[a]) - double(s.info.bounds_min[a]));
    view.extent = extent > 0.0 ? extent : 1.0;
    return view;
}

}  // namespace prt::rt
