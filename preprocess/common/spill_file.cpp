// PointRT preprocess: spill files (spill_file.h).
#include "spill_file.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <utility>

#include "prt/error.h"

namespace prt::pre {

SpillFile::SpillFile(const std::filesystem::path& folder, std::uint64_t bytes, const std::string& what) {
    const std::filesystem::path dir = folder.empty() ? std::filesystem::path(".") : folder;
    auto fail = [&](int err) {
        return Error(dir.string() + ": cannot create a spill file for " + what + ": " + std::strerror(err));
    };
    int fd = -1;
#ifdef O_TMPFILE
    fd = ::open(dir.c_str(), O_TMPFILE | O_RDWR | O_CLOEXEC, 0600);
#endif
    if (fd < 0) {
        std::string name = (dir / "prt-spill-XXXXXX").string();
        fd = ::mkstemp(name.data());
        if (fd < 0) throw fail(errno);
        ::unlink(name.c_str());
    }
    if (bytes > 0) {
        if (::ftruncate(fd, static_cast<off_t>(bytes)) != 0) {
            const int err = errno;
            ::close(fd);
            throw fail(err);
        }
        void* map = ::mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
        const int err = errno;
        ::close(fd);
        if (map == MAP_FAILED) throw fail(err);
        m_data = static_cast<std::byte*>(map);
        m_size = bytes;
    } else {
        ::close(fd);
    }
}

SpillFile::SpillFile(SpillFile&& other) noexcept
    : m_data(std::exchange(other.m_data, nullptr)), m_size(std::exchange(other.m_size, 0)) {}

SpillFile& SpillFile::operator=(SpillFile&& other) noexcept {
    if (this != &other) {
        release();
        m_data = std::exchange(other.m_data, nullptr);
        m_size = std::exchange(other.m_size, 0);
    }
    return *this;
}

SpillFile::~SpillFile() {
    release();
}

void SpillFile::release() {
    if (m_data) ::munmap(m_data, m_size);
    m_data = nullptr;
    m_size = 0;
}

void SpillFile::drop() const {
    drop_pages(m_data, m_size);
}

void drop_pages(const void* data, std::size_t bytes) {
    if (!data || bytes == 0) return;
    const auto page = static_cast<std::uintptr_t>(::sysconf(_SC_PAGESIZE));
    const auto begin = reinterpret_cast<std::uintptr_t>(data);
    const std::uintptr_t first = (begin + page - 1) / page * page, last = (begin + bytes) / page * page;
    if (last > first) ::madvise(reinterpret_cast<void*>(first), last - first, MADV_DONTNEED);
}

std::uint64_t peak_rss_bytes() {
    rusage usage{};
    if (::getrusage(RUSAGE_SELF, &usage) != 0) return 0;
    return std::uint64_t(usage.ru_maxrss) * 1024;  // kilobytes on Linux
}

std::uint64_t current_anon_rss_bytes() {
    std::ifstream in("/proc/self/status");
    std::string key;
    while (in >> key) {
        if (key == "RssAnon:") {
            std::uint64_t kb = 0;
            in >> kb;
            return kb * 1024;
        }
        std::getline(in, key);
    }
    return 0;
}

}  // namespace prt::pre
