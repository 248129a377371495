// PointRT: writing the ISO sections (formats/POOL.md, "Implicit Surface Octree").
#include "iso_pool.h"

#include <vector>

namespace prt::iso {

using pool::SectionType;

void write_iso_sections(IsoModel&& model, pool::PoolWriter& writer) {
    writer.add_array(SectionType::iso_info, std::vector<pool::IsoInfo>{model.info});
    writer.add_array(SectionType::iso_nodes, std::move(model.nodes));
    if (model.info.flags & pool::k_iso_has_q8)
        writer.add_array(SectionType::iso_leaves_q8, std::move(model.leaves_q8));
    else
        writer.remove(SectionType::iso_leaves_q8);
    if (model.info.flags & pool::k_iso_has_f32)
        writer.add_array(SectionType::iso_leaves_f32, std::move(model.leaves_f32));
    else
        writer.remove(SectionType::iso_leaves_f32);
}

core::IsoView make_view(const IsoModel& model, bool prefer_q8) {
    return core::make_iso_view(model.info, model.nodes.data(),
                               model.leaves_q8.empty() ? nullptr : model.leaves_q8.data(),
                               model.leaves_f32.empty() ? nullptr : model.leaves_f32.data(), prefer_q8);
}

}  // namespace prt::iso
