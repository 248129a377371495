// prt-info: what a pool holds: sections, counts, sizes, bytes per point, provenance.
#include <cstdio>

#include <nlohmann/json.hpp>

#include "prt/formats/pool.h"
#include "prt/tool.h"

int main(int argc, char** argv) {
    std::string path;
    bool json_out = false;
    return prt::tool::run(
        argc, argv, "prt-info", "Print the sections, counts, sizes and provenance of a PointRT pool file.",
        [&](CLI::App& app, prt::tool::CommonOptions&) {
            app.add_option("pool", path, "Pool file to describe")->required();
            app.add_flag("--json", json_out, "Print one JSON object instead of a table");
        },
        [&](const prt::tool::CommonOptions&) {
            using namespace prt::pool;
            const PoolFile pool = PoolFile::open(path);
            const ModelInfo& info = pool.model_info();
            const auto prov = nlohmann::json::parse(pool.provenance_json(), nullptr, false);
            if (json_out) {
                nlohmann::json j;
                j["file"] = path;
                j["format_version"] = std::to_string(pool.header().format_major) + "." +
                                      std::to_string(pool.header().format_minor);
                j["file_size"] = pool.file_size();
                j["points"] = info.point_count;
                j["bytes_per_point"] = bytes_per_point(pool);
                j["origin"] = {info.origin[0], info.origin[1], info.origin[2]};
                j["bounds_min"] = {info.bounds_min[0], info.bounds_min[1], info.bounds_min[2]};
                j["bounds_max"] = {info.bounds_max[0], info.bounds_max[1], info.bounds_max[2]};
                for (const SectionEntry& e : pool.sections())
                    j["sections"].push_back({{"name", section_name(static_cast<SectionType>(e.type))},
                                             {"type", e.type}, {"version", e.version}, {"count", e.count},
                                             {"element_size", e.element_size}, {"bytes", e.size},
                                             {"offset", e.offset}});
                if (const auto* oi = pool.find(SectionType::octree_info)) {
                    const OctreeInfo& o = pool.array<OctreeInfo>(SectionType::octree_info)[0];
                    j["octree"] = {{"depth", o.depth}, {"nodes", o.node_count}, {"filled_leaves", o.filled_leaves},
                                   {"splats", o.splat_count}, {"unique_splats", o.unique_splats},
                                   {"replication", o.unique_splats ? double(o.splat_count) / double(o.unique_splats) : 0.0}};
                    (void)oi;
                }
                j["provenance"] = prov;
                std::printf("%s\n", j.dump(2).c_str());
                return;
            }
            std::printf("%s: PointRT pool, format %u.%u, %llu bytes\n", path.c_str(), pool.header().format_major,
                        pool.header().format_minor, static_cast<unsigned long long>(pool.file_size()));
            std::printf("points: %llu   bytes per point: %.1f\n",
                        static_cast<unsigned long long>(info.point_count), bytes_per_point(pool));
            std::printf("origin: (%.9g, %.9g, %.9g)   local bounds: (%g, %g, %g) - (%g, %g, %g)\n", info.origin[0],
                        info.origin[1], info.origin[2], info.bounds_min[0], info.bounds_min[1], info.bounds_min[2],
                        info.bounds_max[0], info.bounds_max[1], info.bounds_max[2]);
            std::printf("\n%-14s %4s %4s %14s %6s %14s %10s\n", "section", "type", "ver", "count", "elem", "bytes", "B/point");
            for (const SectionEntry& e : pool.sections()) {
                std::printf("%-14s %4u %4u %14llu %6u %14llu %10.2f\n", section_name(static_cast<SectionType>(e.type)),
                            e.type, e.version, static_cast<unsigned long long>(e.count), e.element_size,
                            static_cast<unsigned long long>(e.size),
                            info.point_count ? double(e.size) / double(info.point_count) : 0.0);
            }
            if (pool.has(SectionType::octree_info)) {
                const OctreeInfo& o = pool.array<OctreeInfo>(SectionType::octree_info)[0];
                std::printf("\noctree: depth %u, %u nodes, %u filled leaves, %llu splats stored for %llu unique "
                            "(replication %.2fx)%s%s\n",
                            o.depth, o.node_count, o.filled_leaves, static_cast<unsigned long long>(o.splat_count),
                            static_cast<unsigned long long>(o.unique_splats),
                            o.unique_splats ? double(o.splat_count) / double(o.unique_splats) : 0.0,
                            (o.flags & k_octree_replicated) ? ", replicated" : "",
                            (o.flags & k_octree_culled) ? ", culled" : "");
            }
            std::printf("\nprovenance:\n");
            if (prov.is_array())
                for (const auto& step : prov)
                    std::printf("  %s %s  %s  %s\n", step.value("tool", "?").c_str(), step.value("version", "?").c_str(),
                                step.value("time", "").c_str(),
                                step.contains("parameters") ? step["parameters"].dump().c_str() : "{}");
        });
}
