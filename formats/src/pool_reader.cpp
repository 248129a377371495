// PointRT pool file reader: memory-mapped, every read validated (formats/POOL.md, "Validation").

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numeric>
#include <string>
#include <vector>

#include "prt/formats/pool.h"
#include "prt/parallel.h"
#include "section_checks.h"
#include "xxhash_inline.h"

namespace prt::pool {

std::uint64_t checksum(std::span<const std::byte> bytes) {
    return XXH3_64bits(bytes.data(), bytes.size());
}

/// One thread faulting a 175 MB section in page by page was most of prt-cull's one-thread time
/// outside the culling (perf, dev VM).
void map_in_parallel(const std::byte* data, std::size_t bytes) {
    constexpr std::size_t k_page = 4096, k_run = std::size_t{2} << 20;
    if (bytes < 4 * k_run) return;
    const std::size_t pages = (bytes + k_page - 1) / k_page;
    parallel_chunks(pages, k_run / k_page, resolve_threads(0), [&](std::size_t b, std::size_t e, unsigned) {
        for (std::size_t i = b; i < e; ++i) (void)*static_cast<const volatile std::byte*>(data + i * k_page);
    });
}

/// checksum() of a section; on a mapped file, in 64 MiB steps (XXH3 streaming: the same value),
/// each step's pages mapped in parallel first (map_in_parallel) and dropped once hashed.
std::uint64_t checksum_section(std::span<const std::byte> bytes, bool mapped) {
    constexpr std::size_t step = std::size_t{64} << 20;
    if (!mapped) return checksum(bytes);
    if (bytes.size() <= step) {
        map_in_parallel(bytes.data(), bytes.size());
        const std::uint64_t h = checksum(bytes);
        prt::drop_mapped_pages(bytes.data(), bytes.size());
        return h;
    }
    XXH3_state_t state;
    XXH3_INITSTATE(&state);
    XXH3_64bits_reset(&state);
    for (std::size_t at = 0; at < bytes.size(); at += step) {
        const std::size_t n = std::min(step, bytes.size() - at);
        map_in_parallel(bytes.data() + at, n);
        XXH3_64bits_update(&state, bytes.data() + at, n);
        prt::drop_mapped_pages(bytes.data() + at, n);
    }
    return XXH3_64bits_digest(&state);
}

namespace {

std::string entry_label(const SectionEntry& e) {
    const SectionTypeInfo* row = section_type_info(static_cast<SectionType>(e.type));
    return row ? std::string(row->name) : "type " + std::to_string(e.type);
}

}  // namespace

PoolFile::PoolFile(PoolFile&& o) noexcept { *this = std::move(o); }

PoolFile& PoolFile::operator=(PoolFile&& o) noexcept {
    if (this == &o) return *this;
    m_label = std::move(o.m_label);
    m_file = std::move(o.m_file);
    m_owned = std::move(o.m_owned);
    m_options = o.m_options;
    m_size = o.m_size;
    m_data = m_file.data() ? reinterpret_cast<const std::byte*>(m_file.data())
                           : (m_owned.empty() ? nullptr : m_owned.data());
    o.m_data = nullptr;
    o.m_size = 0;
    return *this;
}

PoolFile::~PoolFile() = default;

PoolFile PoolFile::open(const std::filesystem::path& path, const OpenOptions& options) {
    PoolFile pool;
    pool.m_options = options;
    pool.m_label = path.string();
    pool.m_file = MappedFile::open(path, MappedFile::Access::random);
    pool.m_size = pool.m_file.size();
    if (pool.m_size < sizeof(PoolHeader))
        throw Error(pool.m_label + ": header: file is " + std::to_string(pool.m_size) +
                    " bytes, too short for a pool header (truncated or not a pool file)");
    pool.m_data = reinterpret_cast<const std::byte*>(pool.m_file.data());
    pool.validate();
    return pool;
}

PoolFile PoolFile::from_bytes(std::vector<std::byte> bytes, const std::string& label, const OpenOptions& options) {
    PoolFile pool;
    pool.m_options = options;
    pool.m_label = label;
    pool.m_owned = std::move(bytes);
    pool.m_data = pool.m_owned.data();
    pool.m_size = pool.m_owned.size();
    if (pool.m_size < sizeof(PoolHeader))
        throw Error(label + ": header: " + std::to_string(pool.m_size) +
                    " bytes, too short for a pool header (truncated or not a pool file)");
    pool.validate();
    return pool;
}

const PoolHeader& PoolFile::header() const { return *reinterpret_cast<const PoolHeader*>(m_data); }

std::span<const SectionEntry> PoolFile::sections() const {
    const PoolHeader& h = header();
    return {reinterpret_cast<const SectionEntry*>(m_data + h.table_offset), h.section_count};
}

const SectionEntry* PoolFile::find(SectionType type) const {
    for (const SectionEntry& e : sections())
        if (e.type == static_cast<std::uint32_t>(type)) return &e;
    return nullptr;
}

std::span<const std::byte> PoolFile::bytes(const SectionEntry& e) const {
    return {m_data + e.offset, static_cast<std::size_t>(e.size)};
}

const ModelInfo& PoolFile::model_info() const {
    return require<ModelInfo>(SectionType::model_info, "every pool")[0];
}

std::string PoolFile::provenance_json() const {
    const SectionEntry* e = find(SectionType::provenance);
    if (!e) return "[]";
    const auto b = bytes(*e);
    return {reinterpret_cast<const char*>(b.data()), b.size()};
}

void PoolFile::fail(const SectionEntry* entry, const std::string& what) const {
    if (entry) throw Error(m_label + ": section " + entry_label(*entry) + ": " + what);
    throw Error(m_label + ": " + what);
}

void PoolFile::check_element_size(const SectionEntry& e, std::size_t expected) const {
    if (e.element_size != expected)
        fail(&e, "element size " + std::to_string(e.element_size) + ", expected " + std::to_string(expected));
}

void PoolFile::throw_missing(SectionType type, const char* needed_by) const {
    throw Error(m_label + ": section " + section_name(type) + ": missing (needed by " + needed_by + ")");
}

void PoolFile::validate() const {
    const std::uint64_t table_bytes = validate_header();
    validate_sections(table_bytes);
    validate_references(validate_counts());
}

std::uint64_t PoolFile::validate_header() const {
    const PoolHeader& h = header();
    if (std::memcmp(h.magic, k_magic, sizeof k_magic) != 0)
        fail(nullptr, "header: wrong magic (not a PointRT pool file)");
    if (checksum({m_data, offsetof(PoolHeader, header_checksum)}) != h.header_checksum)
        fail(nullptr, "header: bad checksum (file corrupted)");
    if (h.format_major > k_format_major)
        fail(nullptr, "header: format version " + std::to_string(h.format_major) + "." +
                          std::to_string(h.format_minor) + " is newer than this build reads (" +
                          std::to_string(k_format_major) + "." + std::to_string(k_format_minor) +
                          "): update PointRT");
    if (h.format_major < 1) fail(nullptr, "header: format version 0 is invalid");
    if (h.file_size != m_size)
        fail(nullptr, "header: file is " + std::to_string(m_size) + " bytes but the header says " +
                          std::to_string(h.file_size) + (m_size < h.file_size ? " (truncated)" : ""));
    if (h.section_count > k_max_sections)
        fail(nullptr, "header: " + std::to_string(h.section_count) + " sections exceeds the limit of " +
                          std::to_string(k_max_sections));
    const std::uint64_t table_bytes = std::uint64_t(h.section_count) * sizeof(SectionEntry);
    if (h.table_offset < sizeof(PoolHeader) || h.table_offset % alignof(SectionEntry) != 0 ||
        h.table_offset > m_size || table_bytes > m_size - h.table_offset)
        fail(nullptr, "header: section table out of bounds");
    if (checksum({m_data + h.table_offset, static_cast<std::size_t>(table_bytes)}) != h.table_checksum)
        fail(nullptr, "section table: bad checksum (file corrupted)");
    return table_bytes;
}

void PoolFile::validate_sections(std::uint64_t table_bytes) const {
    std::vector<std::pair<std::uint64_t, std::uint64_t>> ranges;
    std::vector<std::size_t> hashed;  // the sections whose checksums are checked here
    const auto table = sections();
    for (std::size_t i = 0; i < table.size(); ++i) {
        const SectionEntry& e = table[i];
        for (std::size_t j = 0; j < i; ++j)
            if (table[j].type == e.type) fail(&e, "appears twice");
        if (e.offset % k_alignment != 0) fail(&e, "payload not 256-byte aligned");
        if (e.offset > m_size || e.size > m_size - e.offset)
            fail(&e, "payload [" + std::to_string(e.offset) + ", +" + std::to_string(e.size) +
                         ") out of bounds of the " + std::to_string(m_size) + "-byte file");
        if (e.element_size == 0) fail(&e, "element size 0");
        if (e.count > e.size / e.element_size || e.count * e.element_size != e.size)
            fail(&e, "count " + std::to_string(e.count) + " x element size " + std::to_string(e.element_size) +
                         " disagrees with size " + std::to_string(e.size));
        if (const SectionTypeInfo* known = section_type_info(static_cast<SectionType>(e.type))) {
            if (e.version > known->version)
                fail(&e, "version " + std::to_string(e.version) + " is newer than this build reads (" +
                             std::to_string(known->version) + "): update PointRT");
            if (e.version == 0) fail(&e, "version 0 is invalid");
            check_element_size(e, known->element_size);
        }
        // Streaming: brick payloads are checked brick by brick as they are read (OpenOptions).
        const bool deferred =
            m_options.defer_brick_payloads && e.type == static_cast<std::uint32_t>(SectionType::brick_data);
        if (!deferred) hashed.push_back(i);
        ranges.emplace_back(e.offset, e.size);
    }
    // The sections' checksums at once, largest first, a section a worker: XXH3 over one section is
    // serial, and one after the other they were most of opening a large pool (the 500M room's
    // 14 GB of points about 2.5 s on the GPU host). Reported in table order.
    std::vector<std::size_t> order(hashed.size());
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
        return table[hashed[a]].size > table[hashed[b]].size;
    });
    std::vector<std::uint64_t> sums(hashed.size());
    const bool mapped = m_owned.empty();
    parallel_chunks(order.size(), 1, resolve_threads(0), [&](std::size_t b, std::size_t, unsigned) {
        sums[order[b]] = checksum_section(bytes(table[hashed[order[b]]]), mapped);
    });
    for (std::size_t k = 0; k < hashed.size(); ++k)
        if (sums[k] != table[hashed[k]].checksum) fail(&table[hashed[k]], "bad checksum (file corrupted)");
    std::sort(ranges.begin(), ranges.end());
    const std::uint64_t table_end = header().table_offset + table_bytes;
    for (std::size_t i = 0; i < ranges.size(); ++i) {
        if (ranges[i].second && ranges[i].first < table_end) fail(nullptr, "a section overlaps the header or table");
        if (i + 1 < ranges.size() && ranges[i].second && ranges[i].first + ranges[i].second > ranges[i + 1].first)
            fail(nullptr, "two sections overlap");
    }
}

const ModelInfo& PoolFile::validate_counts() const {
    const SectionEntry* info_entry = find(SectionType::model_info);
    if (!info_entry) fail(nullptr, "section model_info: missing (every pool has one)");
    const ModelInfo& info = detail::single<ModelInfo>(*this, SectionType::model_info);
    // A bricked pool may drop its per-point sections (prt-bricks without --keep-points: the bricks
    // hold the splats); point_count still says how many points the model was built from.
    if (info.point_count > 0 && !find(SectionType::positions) && !find(SectionType::brick_info))
        fail(nullptr, "section positions: missing (model_info says " + std::to_string(info.point_count) + " points)");
    if (!detail::finite_box(info.bounds_min, info.bounds_max) || !std::isfinite(info.origin[0]) ||
        !std::isfinite(info.origin[1]) || !std::isfinite(info.origin[2]))
        fail(info_entry, "origin or bounds not finite or inverted");
    for (const SectionEntry& e : sections())
        if (section_per_point(static_cast<SectionType>(e.type)) && e.count != info.point_count)
            fail(&e, std::to_string(e.count) + " elements but model_info says " +
                         std::to_string(info.point_count) + " points");
    return info;
}

void PoolFile::validate_references(const ModelInfo& info) const {
    if (const SectionEntry* se = find(SectionType::sensors)) {
        if (se->count == 0 || se->count > k_max_sensors)
            fail(se, std::to_string(se->count) + " sensors, expected 1 to " + std::to_string(k_max_sensors));
        const auto sensors = array<Sensor>(SectionType::sensors);
        for (std::size_t i = 0; i < sensors.size(); ++i) {
            const Sensor& s = sensors[i];
            const double* p = s.position;
            if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]))
                fail(se, "sensor " + std::to_string(i) + ": position not finite");
            if (s.kind != k_sensor_point && s.kind != k_sensor_direction)
                fail(se, "sensor " + std::to_string(i) + ": unknown kind " + std::to_string(s.kind));
            const double len = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
            if (s.kind == k_sensor_direction && !(std::abs(len - 1.0) <= 1e-6))
                fail(se, "sensor " + std::to_string(i) + ": direction not of unit length");
        }
    }
    if (const SectionEntry* ids = find(SectionType::scan_ids)) {
        const SectionEntry* se = find(SectionType::sensors);
        if (!se) fail(ids, "scan_ids without a sensors section");
        const auto v = array<std::uint16_t>(SectionType::scan_ids);
        for (std::size_t i = 0; i < v.size(); ++i)
            if (v[i] >= se->count)
                fail(ids, "point " + std::to_string(i) + ": scan " + std::to_string(v[i]) + " but " +
                              std::to_string(se->count) + " sensors");
    }
    detail::check_splat_octree(*this, info);
    const SectionEntry* prov = find(SectionType::provenance);
    if (prov && prov->size > 0) {
        const auto b = bytes(*prov);
        if (static_cast<char>(b[0]) != '[') fail(prov, "not a JSON array");
    }
}

double bytes_per_point(const PoolFile& pool) {
    const std::uint64_t n = pool.model_info().point_count;
    return n ? static_cast<double>(pool.file_size()) / static_cast<double>(n) : 0.0;
}

}  // namespace prt::pool
