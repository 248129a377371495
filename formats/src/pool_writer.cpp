// PointRT pool file writer: sections laid out 256-byte aligned, checksummed, written atomically
// (temporary file PATH.tmp.HOST.PID in the target folder + fsync + rename, then removal of the
// temporary files of this host's dead writers; formats/POOL.md, "Writing").
#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <chrono>
#include <climits>
#include <cstring>
#include <ctime>
#include <nlohmann/json.hpp>
#include <string_view>

#include "prt/formats/pool.h"

namespace prt::pool {

namespace {

std::uint64_t align_up(std::uint64_t v) { return (v + k_alignment - 1) / k_alignment * k_alignment; }

/// This machine's name for temporary file names: gethostname(), with any character other than
/// letters, digits, '-' and '_' replaced by '_' ('.' included, so the PID after the last '.' of a
/// temporary name is unambiguous); "localhost" when the name is not available.
std::string host_tag() {
    char name[HOST_NAME_MAX + 1] = {};
    if (::gethostname(name, sizeof name - 1) != 0 || name[0] == '\0') return "localhost";
    std::string tag(name);
    for (char& c : tag) {
        const bool keep = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                          c == '-' || c == '_';
        if (!keep) c = '_';
    }
    return tag;
}

/// After a successful rename over PATH: removes the temporary files PATH.tmp.HOST.PID that
/// writers on this host left when they were killed (SIGKILL leaves no chance to clean up).
/// Only names with this host's HOST and a PID that no longer exists (kill(PID, 0) fails with
/// ESRCH) are removed; a live writer's file (its PID exists, EPERM included) and other hosts'
/// files on a shared folder are never touched. Best effort: the pool is already in place, so
/// a folder that cannot be listed or a file that cannot be removed is not an error.
void remove_stale_temporaries(const std::filesystem::path& path, const std::string& host) {
    const std::string prefix = path.filename().string() + ".tmp." + host + ".";
    std::filesystem::path folder = path.parent_path();
    if (folder.empty()) folder = ".";
    std::error_code ec;
    std::filesystem::directory_iterator it(folder, ec);
    for (; !ec && it != std::filesystem::directory_iterator(); it.increment(ec)) {
        const std::string name = it->path().filename().string();
        if (name.size() <= prefix.size() || name.compare(0, prefix.size(), prefix) != 0) continue;
        const std::string_view digits = std::string_view(name).substr(prefix.size());
        long long pid = 0;
        const auto r = std::from_chars(digits.data(), digits.data() + digits.size(), pid);
        if (digits[0] == '0' || r.ec != std::errc() || r.ptr != digits.data() + digits.size() || pid <= 0 ||
            pid > INT_MAX)
            continue;  // not a name this writer makes
        if (static_cast<pid_t>(pid) == ::getpid()) continue;
        if (::kill(static_cast<pid_t>(pid), 0) == 0 || errno != ESRCH) continue;  // alive (or unknown)
        std::error_code ignored;
        std::filesystem::remove(it->path(), ignored);
    }
}

std::string utc_now() {
    const std::time_t t = std::time(nullptr);
    std::tm tm{};
    gmtime_r(&t, &tm);
    char buf[32];
    std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
    return buf;
}

}  // namespace

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

std::vector<std::byte> PoolWriter::serialize() const {
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
        e.checksum = checksum(p.payload);
        const char* name = section_name(p.type);  // informative; long names are cut to 15 bytes
        std::memcpy(e.name, name, std::min(std::strlen(name), sizeof e.name - 1));
        offset = align_up(offset + e.size);
    }
    header.file_size = offset;
    header.table_checksum = checksum({reinterpret_cast<const std::byte*>(table.data()), table.size() * sizeof(SectionEntry)});
    header.header_checksum = checksum({reinterpret_cast<const std::byte*>(&header), offsetof(PoolHeader, header_checksum)});

    std::vector<std::byte> out(header.file_size, std::byte{0});
    std::memcpy(out.data(), &header, sizeof header);
    std::memcpy(out.data() + header.table_offset, table.data(), table.size() * sizeof(SectionEntry));
    for (std::size_t i = 0; i < sections.size(); ++i)
        if (!sections[i].payload.empty())
            std::memcpy(out.data() + table[i].offset, sections[i].payload.data(), sections[i].payload.size());
    return out;
}

std::uint64_t PoolWriter::write(const std::filesystem::path& path) const {
    const std::vector<std::byte> bytes = serialize();
    const std::string host = host_tag();
    const std::string tmp = path.string() + ".tmp." + host + "." + std::to_string(::getpid());
    const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0) throw Error(path.string() + ": cannot create: " + std::strerror(errno));
    auto fail = [&](const char* what) {
        const int err = errno;
        ::close(fd);
        ::unlink(tmp.c_str());
        throw Error(path.string() + ": " + what + ": " + std::strerror(err));
    };
    std::size_t done = 0;
    while (done < bytes.size()) {
        const ssize_t n = ::write(fd, bytes.data() + done, std::min<std::size_t>(bytes.size() - done, 1u << 30));
        if (n < 0) {
            if (errno == EINTR) continue;
            fail("write failed");
        }
        done += static_cast<std::size_t>(n);
    }
    if (::fsync(fd) != 0) fail("fsync failed");
    if (::close(fd) != 0) {
        ::unlink(tmp.c_str());
        throw Error(path.string() + ": close failed: " + std::strerror(errno));
    }
    if (::rename(tmp.c_str(), path.c_str()) != 0) {
        const int err = errno;
        ::unlink(tmp.c_str());
        throw Error(path.string() + ": rename failed: " + std::strerror(err));
    }
    remove_stale_temporaries(path, host);
    return bytes.size();
}

}  // namespace prt::pool
