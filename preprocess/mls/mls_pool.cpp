// PointRT: writing the MLS sections (formats/POOL.md, "MLS surface").
#include "mls_pool.h"

#include <vector>

namespace prt::mls {

using pool::SectionType;

void write_mls_sections(MlsModel&& model, pool::PoolWriter& writer) {
    writer.add_array(SectionType::mls_info, std::vector<pool::MlsInfo>{model.info});
    writer.add_array(SectionType::mls_nodes, std::move(model.nodes));
    writer.add_array(SectionType::mls_refs, std::move(model.refs));
    writer.add_array(SectionType::mls_splats, std::move(model.splats));
    if (model.bvh_nodes.empty()) {  // an earlier tree's BVH would not match this one
        writer.remove(SectionType::mls_bvh_nodes);
        writer.remove(SectionType::mls_bvh_leaves);
    } else {
        writer.add_array(SectionType::mls_bvh_nodes, std::move(model.bvh_nodes));
        writer.add_array(SectionType::mls_bvh_leaves, std::move(model.bvh_leaves));
    }
}

core::MlsView make_view(const MlsModel& model) {
    pool::MlsInfo info = model.info;
    info.node_count = static_cast<std::uint32_t>(model.nodes.size());
    info.ref_count = static_cast<std::uint32_t>(model.refs.size());
    info.splat_count = static_cast<std::uint32_t>(model.splats.size());
    core::MlsView v = core::make_mls_view(info, model.nodes.data(), model.refs.data(), model.splats.data());
    core::attach_mls_bvh(v, model.bvh_nodes.data(), model.bvh_leaves.data(),
                         static_cast<std::uint32_t>(model.bvh_nodes.size()),
                         static_cast<std::uint32_t>(model.bvh_leaves.size()), info.bvh_depth);
    return v;
}

}  // namespace prt::mls
