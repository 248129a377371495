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
}

core::MlsView make_view(const MlsModel& model) {
    pool::MlsInfo info = model.info;
    info.node_count = static_cast<std::uint32_t>(model.nodes.size());
    info.ref_count = static_cast<std::uint32_t>(model.refs.size());
    info.splat_count = static_cast<std::uint32_t>(model.splats.size());
    return core::make_mls_view(info, model.nodes.data(), model.refs.data(), model.splats.data());
}

}  // namespace prt::mls
