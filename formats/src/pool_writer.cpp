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
#include "xxhash_inline.h"

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
    m_sections.push_back(
        {type, element_size, count, payload, payload.size(), nullptr, std::move(keep_alive)});
}

void PoolWriter::add_generated(SectionType type, std::uint32_t element_size, std::uint64_t count,
                               Generator generate) {
    if (element_size == 0 || count > std::numeric_limits<std::uint64_t>::max() / element_size || !generate)
        throw Error(std::string("internal: section ") + section_name(type) + ": bad generated section");
    remove(type);
    m_sections.push_back({type, element_size, count, {}, count * element_size, std::move(generate), nullptr});
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

std::uint64_t PoolWriter::emit(const ByteSink& sink, const ByteSink& rewrite_front) const {
    // Section order: provenance first, then by type, so files are deterministic.
    std::vector<Pending> sections = m_sections;
    sections.push_back({SectionType::provenance,
                        1,
                        m_provenance.size(),
                        {reinterpret_cast<const std::byte*>(m_provenance.data()), m_provenance.size()},
                        m_provenance.size(),
                        nullptr,
                        nullptr});
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
        e.size = p.size;
        e.count = p.count;
        e.element_size = p.element_size;
        const char* name = section_name(p.type);  // informative; long names are cut to 15 bytes
        std::memcpy(e.name, name, std::min(std::strlen(name), sizeof e.name - 1));
        offset = align_up(offset + e.size);
    }
    header.file_size = offset;
    const std::uint64_t front = table[0].offset;  // header, table, padding

    // Front to back: the header and table as zeros (their checksums are not known yet), then each
    // payload after zero padding to its offset, hashed as it is handed over (one pass over the data:
    // hashing first and writing after read a mapped section twice).
    static const std::byte zeros[k_alignment] = {};
    std::uint64_t at = 0;
    auto pad_to = [&](std::uint64_t target) {
        while (at < target) {
            const std::size_t n = static_cast<std::size_t>(std::min<std::uint64_t>(target - at, k_alignment));
            sink(zeros, n);
            at += n;
        }
    };
    pad_to(front);
    XXH3_state_t state;
    for (std::size_t i = 0; i < sections.size(); ++i) {
        const Pending& p = sections[i];
        pad_to(table[i].offset);
        const bool hash = !p.checksum_known;
        if (hash) {
            XXH3_INITSTATE(&state);
            XXH3_64bits_reset(&state);
        }
        // Hashed and written in pieces that stay in the cache between the two.
        constexpr std::size_t piece = std::size_t{1} << 20;
        auto take = [&](const std::byte* data, std::size_t n) {
            for (std::size_t done = 0; done < n; done += piece) {
                const std::size_t k = std::min(piece, n - done);
                if (hash) XXH3_64bits_update(&state, data + done, k);
                sink(data + done, k);
            }
        };
        if (p.generate) {
            std::uint64_t handed = 0;
            p.generate([&](const std::byte* data, std::size_t n) {
                if (n > p.size - handed)
                    throw Error(std::string("internal: section ") + section_name(p.type) +
                                ": the generator handed over more bytes than the section holds");
                handed += n;
                take(data, n);
            });
            if (handed != p.size)
                throw Error(std::string("internal: section ") + section_name(p.type) +
                            ": the generator handed over fewer bytes than the section holds");
        } else {
            const std::span<const std::byte> payload = p.payload;
            constexpr std::size_t step = std::size_t{64} << 20;
            for (std::size_t done = 0; done < payload.size(); done += step) {
                const std::size_t n = std::min(step, payload.size() - done);
                if (p.file_mapped && hash) map_in_parallel(payload.data() + done, n);
                take(payload.data() + done, n);
                if (p.file_mapped) drop_mapped_pages(payload.data() + done, n);
            }
        }
        at += p.size;
        table[i].checksum = hash ? XXH3_64bits_digest(&state) : p.checksum;
    }
    pad_to(header.file_size);

    header.table_checksum =
        checksum({reinterpret_cast<const std::byte*>(table.data()), table.size() * sizeof(SectionEntry)});
    header.header_checksum =
        checksum({reinterpret_cast<const std::byte*>(&header), offsetof(PoolHeader, header_checksum)});
    std::vector<std::byte> head(front, std::byte{0});
    std::memcpy(head.data(), &header, sizeof header);
    std::memcpy(head.data() + header.table_offset, table.data(), table.size() * sizeof(SectionEntry));
    rewrite_front(head.data(), head.size());
    return header.file_size;
}

std::vector<std::byte> PoolWriter::serialize() const {
    std::vector<std::byte> out;
    emit([&](const std::byte* data, std::size_t n) { out.insert(out.end(), data, data + n); },
         [&](const std::byte* data, std::size_t n) { std::memcpy(out.data(), data, n); });
    return out;
}

std::uint64_t PoolWriter::write(const std::filesystem::path& path) const {
    AtomicFile file(path);
    const std::uint64_t bytes =
        emit([&](const std::byte* data, std::size_t n) { file.write(data, n); },
             [&](const std::byte* data, std::size_t n) { file.write_at(0, data, n); });
    file.commit();
    return bytes;
}

}  // namespace prt::pool
