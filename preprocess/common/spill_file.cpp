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

namespace {

/// A new temporary read-write file in `folder`, already removed from it.
int temporary_file(const std::filesystem::path& folder, const std::string& what) {
    const std::filesystem::path dir = folder.empty() ? std::filesystem::path(".") : folder;
    int fd = -1;
#ifdef O_TMPFILE
    fd = ::open(dir.c_str(), O_TMPFILE | O_RDWR | O_CLOEXEC, 0600);
#endif
    if (fd < 0) {
        std::string name = (dir / "prt-spill-XXXXXX").string();
        fd = ::mkstemp(name.data());
        if (fd < 0)
            throw Error(dir.string() + ": cannot create a spill file for " + what + ": " +
                        std::strerror(errno));
        ::unlink(name.c_str());
    }
    return fd;
}

/// pwrite of all `bytes` at `offset`; throws prt::Error "spill file for WHAT: write failed: REASON".
void write_fully(int fd, std::uint64_t offset, const void* data, std::uint64_t bytes,
                 const std::string& what) {
    const auto* p = static_cast<const char*>(data);
    for (std::uint64_t done = 0; done < bytes;) {
        const ssize_t n =
            ::pwrite(fd, p + done, static_cast<std::size_t>(bytes - done), static_cast<off_t>(offset + done));
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0)
            throw Error("spill file for " + what +
                        ": write failed: " + std::strerror(n < 0 ? errno : ENOSPC));
        done += static_cast<std::uint64_t>(n);
    }
}

}  // namespace

SpillFile::SpillFile(const std::filesystem::path& folder, std::uint64_t bytes, const std::string& what) {
    const std::filesystem::path dir = folder.empty() ? std::filesystem::path(".") : folder;
    m_what = what;
    map(temporary_file(folder, what), bytes, dir.string() + ": cannot create a spill file for " + what);
}

SpillFile SpillFile::named(const std::filesystem::path& file, std::uint64_t bytes, const std::string& what) {
    const std::string failure = file.string() + ": cannot create " + what;
    const int fd = ::open(file.c_str(), O_RDWR | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0) throw Error(failure + ": " + std::strerror(errno));
    SpillFile f;
    f.m_what = what;
    f.map(fd, bytes, failure);
    return f;
}

void SpillFile::map(int fd, std::uint64_t bytes, const std::string& failure) {
    int err = 0;
    if (bytes > 0 && ::ftruncate(fd, static_cast<off_t>(bytes)) != 0) {
        err = errno;
    } else if (bytes > 0) {
        void* map = ::mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
        if (map == MAP_FAILED)
            err = errno;
        else
            m_data = static_cast<std::byte*>(map), m_size = bytes;
    }
    if (err != 0) {
        ::close(fd);
        throw Error(failure + ": " + std::strerror(err));
    }
    m_fd = fd;
}

void SpillFile::write_at(std::uint64_t offset, const void* data, std::uint64_t bytes) const {
    write_fully(m_fd, offset, data, bytes, m_what);
}

AppendFile::AppendFile(const std::filesystem::path& folder, const std::string& what)
    : m_fd(temporary_file(folder, what)), m_what(what) {}

AppendFile::AppendFile(AppendFile&& other) noexcept
    : m_fd(std::exchange(other.m_fd, -1)),
      m_size(other.m_size.exchange(0)),
      m_what(std::move(other.m_what)) {}

AppendFile& AppendFile::operator=(AppendFile&& other) noexcept {
    if (this != &other) {
        if (m_fd >= 0) ::close(m_fd);
        m_fd = std::exchange(other.m_fd, -1);
        m_size = other.m_size.exchange(0);
        m_what = std::move(other.m_what);
    }
    return *this;
}

AppendFile::~AppendFile() {
    if (m_fd >= 0) ::close(m_fd);
}

std::uint64_t AppendFile::append(const void* data, std::uint64_t bytes) {
    const std::uint64_t at = m_size.fetch_add(bytes);
    write_fully(m_fd, at, data, bytes, m_what);
    return at;
}

void AppendFile::read(std::uint64_t offset, void* out, std::uint64_t bytes) const {
    auto* p = static_cast<char*>(out);
    for (std::uint64_t done = 0; done < bytes;) {
        const ssize_t n = ::pread(m_fd, p + done, static_cast<std::size_t>(bytes - done),
                                  static_cast<off_t>(offset + done));
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0)
            throw Error("spill file for " + m_what +
                        ": read failed: " + (n < 0 ? std::strerror(errno) : "end of file"));
        done += static_cast<std::uint64_t>(n);
    }
}

SpillFile::SpillFile(SpillFile&& other) noexcept
    : m_data(std::exchange(other.m_data, nullptr)),
      m_size(std::exchange(other.m_size, 0)),
      m_fd(std::exchange(other.m_fd, -1)),
      m_what(std::move(other.m_what)) {}

SpillFile& SpillFile::operator=(SpillFile&& other) noexcept {
    if (this != &other) {
        release();
        m_data = std::exchange(other.m_data, nullptr);
        m_size = std::exchange(other.m_size, 0);
        m_fd = std::exchange(other.m_fd, -1);
        m_what = std::move(other.m_what);
    }
    return *this;
}

SpillFile::~SpillFile() {
    release();
}

SpillReleaser::SpillReleaser() : m_thread([this] { run(); }) {}

SpillReleaser::~SpillReleaser() {
    {
        const std::lock_guard<std::mutex> lock(m_mutex);
        m_stop = true;
    }
    m_ready.notify_one();
    m_thread.join();
}

void SpillReleaser::release(SpillFile&& file) {
    {
        const std::lock_guard<std::mutex> lock(m_mutex);
        m_queue.push_back(std::move(file));
    }
    m_ready.notify_one();
}

void SpillReleaser::run() {
    std::unique_lock<std::mutex> lock(m_mutex);
    for (;;) {  // ends when stopped with nothing left to close
        m_ready.wait(lock, [this] { return m_stop || !m_queue.empty(); });
        if (m_queue.empty()) return;
        std::vector<SpillFile> files = std::move(m_queue);
        m_queue.clear();
        lock.unlock();
        files.clear();  // the closes, outside the lock
        lock.lock();
    }
}

void SpillFile::release() {
    if (m_data) ::munmap(m_data, m_size);
    if (m_fd >= 0) ::close(m_fd);
    m_data = nullptr;
    m_size = 0;
    m_fd = -1;
}

void SpillFile::drop() const {
    drop_pages(m_data, m_size);
}

void SpillFile::advise_random() const {
    if (m_data && m_size > 0) ::madvise(m_data, m_size, MADV_RANDOM);
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

namespace {

/// A "Rss...:" line of /proc/self/status in bytes (0 when absent).
std::uint64_t status_bytes(const std::string& field) {
    std::ifstream in("/proc/self/status");
    std::string key;
    while (in >> key) {
        if (key == field) {
            std::uint64_t kb = 0;
            in >> kb;
            return kb * 1024;
        }
        std::getline(in, key);
    }
    return 0;
}

}  // namespace

std::uint64_t current_anon_rss_bytes() {
    return status_bytes("RssAnon:");
}

std::uint64_t current_file_rss_bytes() {
    return status_bytes("RssFile:");
}

}  // namespace prt::pre
