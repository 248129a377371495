// PointRT pool file writer: sections laid out 256-byte aligned, checksummed, written atomically
// (prt/atomic_file.h: temporary file PATH.tmp.HOST.PID in the target folder + fsync + rename, then
// removal of the temporary files of this host's dead writers; formats/POOL.md, "Writing").
#include <algorithm>
#include <chrono>
#include <cstring>
#include <ctime>
#include <limits>
#include <nlohmann/json.hpp>

#include "prt/atomic_file.h"
#include "prt/formats/pool.h"

namespace prt::pool {

namespace {

std::uint64_t align_up(std::uint64_t v) { return (v + k_alignment - 1) / k_alignment * k_alignment; }

std::string utc_now() {
    const std::time_t t = std::time(nullptr);
    std::tm tm{};
    gmtime_r(&t, &tm);
    char buf[32];
    std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
    return buf;
}

}  // namespace

void set_point_bounds(ModelInfo& info, std::span<const Float3> local) {
    float lo[3] = {std::numeric_limits<float>::max(), std::numeric_limits<float>::max(),
                   std::numeric_limits<float>::max()};
    float hi[3] = {-lo[0], -lo[1], -lo[2]};
    for (const Float3& p : local) {
        const float v[3] = {p.x, p.y, p.z};
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], v[a]);
            hi[a] = std::max(hi[a], v[a]);
        }
    }
    for (int a = 0; a < 3; ++a) {
        info.bounds_min[a] = lo[a];
        info.bounds_max[a] = hi[a];
    }
    info.point_count = local.size();
}

void PoolWriter::add_shared(SectionType type, std::uint32_t element_size, std::uint64_t count,
                            std::span<const std::byte> payload, std::shared_ptr<const void> keep_alive) {
    if (element_size == 0 || payload.size() != count * element_size)
        throw Error(std::string("internal: section ") + section_name(type) + ": payload size mismatch");
    remove(type);
    m_sections.push_back({type, element_size, count, payload, std::move(keep_alive)});
}

void PoolWriter::add(SectionType type, std::uint32_t element_size, std::uint64_t count,
                     std::span<const std::byte> payload) {
    auto holder = std::make_shared<std::vector<std::byte>>(payload.begin(), payload.end());
    add_shared(type, element_size, count, {holder->data(), holder->size()},
               std::shared_ptr<const void>(holder, holder.get()));
}

void PoolWriter::carry_over(const PoolFile& source) {
    for (const SectionEntry& e : source.sections()) {
        const auto type = static_cast<SectionType>(e.type);
        if (type == SectionType::provenance) {
            m_provenance = source.provenance_json();
            continue;
        }
        add_shared(type, e.element_size, e.count, source.bytes(e), nullptr);
        m_sections.back().file_mapped = source.mapped();
        if (!(source.options().defer_brick_payloads && type == SectionType::brick_data)) {
            m_sections.back().checksum_known = true;  // open() checked it against the payload
            m_sections.back().checksum = e.checksum;
        }
    }
}

void PoolWriter::remove(SectionType type) {
    std::erase_if(m_sections, [type](const Pending& p) { return p.type == type; });
}

bool PoolWriter::has(SectionType type) const {
    return std::any_of(m_sections.begin(), m_sections.end(), [type](const Pending& p) { return p.type == type; });
}

void PoolWriter::add_provenance(const std::string& tool, const std::string& version,
                                const std::string& parameters_json) {
    nlohmann::json list = nlohmann::json::parse(m_provenance, nullptr, false);
    if (!list.is_array()) list = nlohmann::json::array();
    nlohmann::json params = nlohmann::json::parse(parameters_json, nullptr, false);
    if (params.is_discarded()) params = parameters_json;
    list.push_back({{"tool", tool}, {"version", version}, {"parameters", params}, {"time", utc_now()}});
    m_provenance = list.dump();
}

std::uint64_t PoolWriter::emit(const std::function<void(const std::byte*, std::size_t)>& sink) const {
    // Section order: provenance first, then by type, so files are deterministic.
    std::vector<Pending> sections = m_sections;
    sections.push_back({SectionType::provenance, 1, m_provenance.size(),
                        {reinterpret_cast<const std::byte*>(m_provenance.data()), m_provenance.size()}, nullptr});
    std::stable_sort(sections.begin(), sections.end(),
                     [](const Pending& a, const Pending& b) { return a.type < b.type; });
    if (sections.size() > k_max_sections) throw Error("too many sections");

    PoolHeader header{};
    std::memcpy(header.magic, k_magic, sizeof k_magic);
    header.format_major = k_format_major;
    header.format_minor = k_format_minor;
    header.section_count = static_cast<std::uint32_t>(sections.size());
    header.table_offset = sizeof(PoolHeader);
    std::vector<SectionEntry> table(sections.size());
    std::uint64_t offset = align_up(header.table_offset + table.size() * sizeof(SectionEntry));
    for (std::size_t i = 0; i < sections.size(); ++i) {
        const Pending& p = sections[i];
        SectionEntry& e = table[i];
        e.type = static_cast<std::uint32_t>(p.type);
        e.version = section_version(p.type);
        e.offset = offset;
        e.size = p.payload.size();
        e.count = p.count;
        e.element_size = p.element_size;
        e.checksum = p.checksum_known ? p.checksum : checksum_section(p.payload, p.file_mapped);
        const char* name = section_name(p.type);  // informative; long names are cut to 15 bytes
        std::memcpy(e.name, name, std::min(std::strlen(name), sizeof e.name - 1));
        offset = align_up(offset + e.size);
    }
    header.file_size = offset;
    header.table_checksum =
        checksum({reinterpret_cast<const std::byte*>(table.data()), table.size() * sizeof(SectionEntry)});
    header.header_checksum =
        checksum({reinterpret_cast<const std::byte*>(&header), offsetof(PoolHeader, header_checksum)});

    // Front to back: header, table, then each payload after zero padding to its offset.
    static const std::byte zeros[k_alignment] = {};
    std::uint64_t at = 0;
    auto pad_to = [&](std::uint64_t target) {
        while (at < target) {
            const std::size_t n = static_cast<std::size_t>(std::min<std::uint64_t>(target - at, k_alignment));
            sink(zeros, n);
            at += n;
        }
    };
    sink(reinterpret_cast<const std::byte*>(&header), sizeof header);
    at = sizeof header;
    pad_to(header.table_offset);
    sink(reinterpret_cast<const std::byte*>(table.data()), table.size() * sizeof(SectionEntry));
    at += table.size() * sizeof(SectionEntry);
    for (std::size_t i = 0; i < sections.size(); ++i) {
        pad_to(table[i].offset);
        const std::span<const std::byte> payload = sections[i].payload;
        constexpr std::size_t chunk = std::size_t{64} << 20;
        for (std::size_t done = 0; done < payload.size(); done += chunk) {
            const std::size_t n = std::min(chunk, payload.size() - done);
            sink(payload.data() + done, n);
            if (sections[i].file_mapped) drop_mapped_pages(payload.data() + done, n);
        }
        at += payload.size();
    }
    pad_to(header.file_size);
    return header.file_size;
}

std::vector<std::byte> PoolWriter::serialize() const {
    std::vector<std::byte> out;
    emit([&](const std::byte* data, std::size_t n) { out.insert(out.end(), data, data + n); });
    return out;
}

std::uint64_t PoolWriter::write(const std::filesystem::path& path) const {
    AtomicFile file(path);
    const std::uint64_t bytes = emit([&](const std::byte* data, std::size_t n) { file.write(data, n); });
    file.commit();
    return bytes;
}

}  // namespace prt::pool
