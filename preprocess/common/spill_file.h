// PointRT preprocess: spill files for the out-of-core builds (issue 17). A spill file is a temporary
// file, removed from its folder as soon as it is created (nothing is left behind if the tool is
// killed), memory-mapped read-write and shared, so a big array (a tool's output section, the
// points sorted by tile) lives in the page cache and on disk instead of in the process's memory;
// the kernel writes its pages back and reclaims them under pressure. drop_pages() unmaps the pages
// a pass is done with, which keeps the resident set (and getrusage's peak) of a long pass bounded.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <mutex>
#include <span>
#include <string>
#include <thread>
#include <vector>

namespace prt::pre {

/// A temporary read-write memory-mapped file of a fixed size (zero-filled, sparse). Move-only.
class SpillFile {
public:
    SpillFile() = default;
    /// Creates a file of `bytes` in `folder` (O_TMPFILE, or a unique name removed at once) and
    /// maps it. Throws prt::Error "FOLDER: cannot create a spill file for WHAT: REASON".
    SpillFile(const std::filesystem::path& folder, std::uint64_t bytes, const std::string& what);
    /// A named file `file` of `bytes` (created or truncated) mapped read-write; it stays on disk after
    /// the mapping is gone (the staged out-of-core build hands it to other processes, issue 21).
    /// Throws prt::Error "FILE: cannot create WHAT: REASON".
    static SpillFile named(const std::filesystem::path& file, std::uint64_t bytes, const std::string& what);
    SpillFile(SpillFile&& other) noexcept;
    SpillFile& operator=(SpillFile&& other) noexcept;
    SpillFile(const SpillFile&) = delete;
    SpillFile& operator=(const SpillFile&) = delete;
    ~SpillFile();

    std::byte* data() const { return m_data; }
    std::uint64_t size() const { return m_size; }
    template <class T>
    std::span<T> as() const {
        return {reinterpret_cast<T*>(m_data), static_cast<std::size_t>(m_size / sizeof(T))};
    }
    /// drop_pages() over the whole mapping (the contents stay in the file).
    void drop() const;
    /// For a file read and written at random (a graph's lists, per-point arrays of a propagation):
    /// MADV_RANDOM over the mapping, which must come before its pages are first touched. Without
    /// it the page cache holds the file in large folios (Linux 6.x, ext4 among others), a fault maps
    /// the whole folio, and scattered accesses between two drop() calls map most of the file: 4096
    /// random reads of a 576 MB spill file left 574 MB resident on the dev VM (6.18), against 16 MB
    /// for 4096 writes and about 64 KB a read (the fault-around) with the advice. Under a memory
    /// limit the large folios were also written back and read again whole.
    void advise_random() const;
    /// Writes `bytes` at `offset` through the file (pwrite) rather than the mapping, which then reads
    /// them: a scattered write of many pages costs a copy into the page cache instead of a page fault
    /// per page. Safe from several threads on disjoint ranges. Throws prt::Error "spill file for
    /// WHAT: write failed: REASON".
    void write_at(std::uint64_t offset, const void* data, std::uint64_t bytes) const;

private:
    /// Sizes the open file `fd` to `bytes` and maps it (keeping `fd` for write_at); throws prt::Error
    /// "FAILURE: REASON".
    void map(int fd, std::uint64_t bytes, const std::string& failure);
    void release();
    std::byte* m_data = nullptr;
    std::uint64_t m_size = 0;
    int m_fd = -1;
    std::string m_what;
};

/// A temporary file written by appending (its final size unknown) and read back at offsets; removed
/// from its folder at creation, like SpillFile. Move-only.
class AppendFile {
public:
    AppendFile() = default;
    /// Throws prt::Error "FOLDER: cannot create a spill file for WHAT: REASON".
    AppendFile(const std::filesystem::path& folder, const std::string& what);
    AppendFile(AppendFile&& other) noexcept;
    AppendFile& operator=(AppendFile&& other) noexcept;
    AppendFile(const AppendFile&) = delete;
    AppendFile& operator=(const AppendFile&) = delete;
    ~AppendFile();

    /// Appends `bytes` bytes; returns the offset they start at. Throws prt::Error on a write error.
    /// Several threads may append at once: each call reserves its range first, then writes it
    /// (the writes of concurrent calls overlap; none waits for another's).
    std::uint64_t append(const void* data, std::uint64_t bytes);
    /// Reads `bytes` bytes at `offset` (written before) into `out`. Throws prt::Error on a read error.
    void read(std::uint64_t offset, void* out, std::uint64_t bytes) const;
    std::uint64_t size() const { return m_size.load(); }

private:
    int m_fd = -1;
    std::atomic<std::uint64_t> m_size{0};
    std::string m_what;
};

/// Closes spill files on a thread of its own. Closing a temporary file removes it, and removing a
/// file waits for the writes the kernel has started of its dirty pages (its pages not yet written
/// are dropped): after the 500M room's cells, closing its 16 GB of point records took about 6 s of
/// nothing but waiting for the disk (H100 host). A build hands each file over once it is done with
/// it; the destructor waits for the files handed over (by then long closed, as a rule).
class SpillReleaser {
public:
    SpillReleaser();
    ~SpillReleaser();
    SpillReleaser(const SpillReleaser&) = delete;
    SpillReleaser& operator=(const SpillReleaser&) = delete;
    /// Takes `file` (left empty) and closes it on the releasing thread.
    void release(SpillFile&& file);

private:
    void run();
    std::mutex m_mutex;
    std::condition_variable m_ready;
    std::vector<SpillFile> m_queue;
    bool m_stop = false;
    std::thread m_thread;
};

/// Unmaps the whole pages inside [data, data + bytes) of a file mapping from the process
/// (madvise MADV_DONTNEED): a read-only mapping or a shared one re-reads them from the file (or
/// the page cache) when touched again. Never call it on anonymous memory (it would zero it).
void drop_pages(const void* data, std::size_t bytes);

/// The process's peak resident set in bytes (getrusage ru_maxrss) and its current anonymous
/// resident memory (/proc/self/status RssAnon; 0 when unknown), for the out-of-core statistics.
std::uint64_t peak_rss_bytes();
std::uint64_t current_anon_rss_bytes();
/// The file pages this process maps now (/proc/self/status RssFile; 0 when unknown).
std::uint64_t current_file_rss_bytes();

}  // namespace prt::pre
