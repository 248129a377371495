// PointRT: the one atomic file write of the project (pools, images, JSON results). The bytes go to a
// temporary file PATH.tmp.HOST.PID in the target folder, which is fsynced and renamed over PATH, so a
// reader never sees a partial file under the final name and a failed or killed run leaves PATH as it
// was (formats/POOL.md, "Writing"). After the rename, the temporary files of this host's writers of
// PATH that were killed are removed.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>

namespace prt {

/// A file written through a temporary name and renamed over its path on commit(). Move-free; the
/// destructor removes the temporary file unless commit() succeeded. Errors throw prt::Error with
/// one line "PATH: what: reason".
class AtomicFile {
public:
    /// `keep_extension`: the temporary name ends with PATH's extension too (for libraries that
    /// choose a format by the name they write to).
    explicit AtomicFile(std::filesystem::path path, bool keep_extension = false);
    ~AtomicFile();
    AtomicFile(const AtomicFile&) = delete;
    AtomicFile& operator=(const AtomicFile&) = delete;

    const std::filesystem::path& path() const { return m_path; }
    /// The temporary file's name (for writers that open it themselves).
    const std::string& temporary() const { return m_tmp; }
    /// Appends n bytes (the temporary file is created on the first call). On Linux, every
    /// k_writeback_chunk bytes written start their write-back to the disk (sync_file_range), so
    /// commit()'s fsync waits for the tail only and a large file's disk writes overlap its copy
    /// into the page cache.
    void write(const void* data, std::size_t n);
    /// Writes n bytes over the file's bytes at `offset`, all of which write() has written already
    /// (a header whose checksums are known once the rest is written).
    void write_at(std::uint64_t offset, const void* data, std::size_t n);
    /// fsync, rename over path(), then removal of this host's dead writers' temporary files.
    void commit();

private:
    void open();
    [[noreturn]] void fail(const char* what, int err);

    std::filesystem::path m_path;
    std::string m_host;
    std::string m_tmp;
    void start_writeback(bool all);

    int m_fd = -1;
    bool m_committed = false;
    std::uint64_t m_written = 0;    ///< bytes written so far
    std::uint64_t m_scheduled = 0;  ///< bytes whose write-back was started
    bool m_writeback = true;        ///< false once sync_file_range failed (not supported here)
};

/// Checks up front that AtomicFile(path) can be written and committed, so that a tool refuses an
/// unwritable output before it does the work: `path` is not a folder, its folder exists and is a
/// folder, and a temporary file can be created there (created and removed at once; this catches
/// missing permission and read-only file systems). Throws prt::Error "PATH: cannot write: reason".
void check_writable(const std::filesystem::path& path);

/// Writes `bytes` to `path` atomically (AtomicFile).
void write_file_atomic(const std::filesystem::path& path, std::span<const std::byte> bytes);
/// Writes `text` to `path` atomically (AtomicFile).
void write_file_atomic(const std::filesystem::path& path, std::string_view text);

}  // namespace prt
