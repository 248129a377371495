// PointRT: a read-only memory-mapped file. The import readers parse straight out of the page cache
// (no per-line stream reads, no copies); the pool reader maps a pool and validates it in place.
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>

namespace prt {

/// A whole file mapped read-only. Move-only. An empty file maps to an empty view.
class MappedFile {
public:
    /// How the file will be read: front to back once (the import readers: aggressive read-ahead)
    /// or anywhere (a pool's sections).
    enum class Access { sequential, random };

    /// Maps `path`; throws prt::Error "PATH: cannot open: REASON" (or "cannot stat", "is a
    /// directory, not a file", "not a regular file", "cannot map").
    static MappedFile open(const std::filesystem::path& path, Access access = Access::sequential);

    MappedFile() = default;  ///< nothing mapped
    MappedFile(MappedFile&& other) noexcept;
    MappedFile& operator=(MappedFile&& other) noexcept;
    MappedFile(const MappedFile&) = delete;
    MappedFile& operator=(const MappedFile&) = delete;
    ~MappedFile();

    const char* data() const { return m_data; }
    std::size_t size() const { return m_size; }
    std::string_view view() const { return {m_data, m_size}; }
    /// The path as given, for error messages.
    const std::string& label() const { return m_label; }

private:
    void release();

    const char* m_data = nullptr;
    std::size_t m_size = 0;
    std::string m_label;
};

/// Unmaps the whole pages inside [data, data + bytes) of a read-only or shared file mapping from
/// the process (madvise MADV_DONTNEED); they are read again from the page cache or the file when
/// touched. Keeps the resident set of a pass over a file larger than memory bounded (issue 17).
/// Never call it on anonymous memory: that would zero it.
void drop_mapped_pages(const void* data, std::size_t bytes);

}  // namespace prt
