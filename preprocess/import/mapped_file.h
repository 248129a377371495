// PointRT prt-import: a read-only memory-mapped input file (the readers parse straight out of the
// page cache: no per-line stream reads, no copies).
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>

namespace prt::pre::import {

/// A whole file mapped read-only. Move-only. An empty file maps to an empty view.
class MappedFile {
public:
    /// Maps `path`; throws prt::Error "PATH: cannot open: REASON" (or "is a directory").
    static MappedFile open(const std::filesystem::path& path);

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
    MappedFile() = default;
    void release();

    const char* m_data = nullptr;
    std::size_t m_size = 0;
    std::string m_label;
};

}  // namespace prt::pre::import
