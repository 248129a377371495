// PointRT pool file: reader (memory-mapped, validated) and writer (atomic: temporary file + rename).
// Host-only. Layout in pool_layout.h, specification in formats/POOL.md.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "prt/error.h"
#include "prt/formats/pool_layout.h"
#include "prt/formats/section_table.h"
#include "prt/mapped_file.h"

namespace prt::pool {

/// How a pool is opened.
struct OpenOptions {
    /// Streaming (issue 17): leave the brick_data section's whole-payload checksum unchecked at
    /// open, since computing it reads every brick of a pool that may be far larger than memory.
    /// Every other check runs as usual; each brick carries its own XXH3-64 in brick_table and is
    /// checked alone when it is read or uploaded (validate_brick in prt/formats/brick_sections.h).
    bool defer_brick_payloads = false;
};

/// A validated, read-only, memory-mapped pool file. Opening checks everything POOL.md lists
/// (magic, versions, sizes, bounds, overlaps, checksums, counts, cross-references, the splat
/// octree) and throws prt::Error with one line "FILE: section NAME: what is wrong" on the first
/// problem found. The surface and global-illumination sections are checked when a reader asks for
/// them (validate_iso, validate_mls, validate_patches, validate_caustic_maps, validate_light_map in
/// prt/formats/*_sections.h). Move-only; views stay valid while the PoolFile lives.
class PoolFile {
public:
    static PoolFile open(const std::filesystem::path& path, const OpenOptions& options = {});
    /// Validates an in-memory image (used by open() and by the fuzz target); `label` names it in errors.
    static PoolFile from_bytes(std::vector<std::byte> bytes, const std::string& label,
                               const OpenOptions& options = {});
    /// The options the pool was opened with (brick payloads deferred: check each brick alone).
    const OpenOptions& options() const { return m_options; }

    PoolFile(PoolFile&&) noexcept;
    PoolFile& operator=(PoolFile&&) noexcept;
    ~PoolFile();

    const std::string& label() const { return m_label; }
    const PoolHeader& header() const;
    std::span<const SectionEntry> sections() const;
    std::uint64_t file_size() const { return m_size; }
    /// The whole file image (header, table, payloads).
    std::span<const std::byte> file_bytes() const { return {m_data, static_cast<std::size_t>(m_size)}; }

    /// The entry of a section type, or nullptr when absent.
    const SectionEntry* find(SectionType type) const;
    bool has(SectionType type) const { return find(type) != nullptr; }
    /// Whether the pool is a file mapping (open()), not bytes in memory (from_bytes()).
    bool mapped() const { return m_owned.empty(); }
    std::span<const std::byte> bytes(const SectionEntry& entry) const;

    /// Typed view of a section; an empty span when absent. Throws if the element size differs.
    template <class T>
    std::span<const T> array(SectionType type) const {
        const SectionEntry* e = find(type);
        if (!e) return {};
        check_element_size(*e, sizeof(T));
        return {reinterpret_cast<const T*>(m_data + e->offset), static_cast<std::size_t>(e->count)};
    }
    /// Typed view of a section that must be present (throws "FILE: section NAME: missing ...").
    template <class T>
    std::span<const T> require(SectionType type, const char* needed_by) const {
        if (!find(type)) throw_missing(type, needed_by);
        return array<T>(type);
    }

    /// The model_info section (every valid pool has one).
    const ModelInfo& model_info() const;
    /// The provenance JSON text ("[]" when absent).
    std::string provenance_json() const;

    /// Throws prt::Error "LABEL: section NAME: what".
    [[noreturn]] void fail(const SectionEntry* entry, const std::string& what) const;

private:
    PoolFile() = default;
    // POOL.md "Validation", in its order: 1. header and table, 2. each section, 3. counts that must
    // agree, 4. cross-references.
    void validate() const;
    std::uint64_t validate_header() const;  // returns the table's size in bytes
    void validate_sections(std::uint64_t table_bytes) const;
    const ModelInfo& validate_counts() const;
    void validate_references(const ModelInfo& info) const;
    void check_element_size(const SectionEntry& e, std::size_t expected) const;
    [[noreturn]] void throw_missing(SectionType type, const char* needed_by) const;

    std::string m_label;
    const std::byte* m_data = nullptr;
    std::uint64_t m_size = 0;
    MappedFile m_file;                 // the file when mapped
    std::vector<std::byte> m_owned;    // storage when built from bytes
    OpenOptions m_options;
};

/// Builds a pool in memory and writes it atomically. Sections are either owned buffers or views
/// into a PoolFile being carried over (which must outlive write()).
class PoolWriter {
public:
    /// Adds (or replaces) a section from raw bytes, copied.
    void add(SectionType type, std::uint32_t element_size, std::uint64_t count,
             std::span<const std::byte> payload);
    /// Adds (or replaces) a section, taking ownership of a vector of elements.
    template <class T>
    void add_array(SectionType type, std::vector<T> elements) {
        const std::uint64_t count = elements.size();
        auto holder = std::make_shared<std::vector<T>>(std::move(elements));
        add_shared(type, sizeof(T), count,
                   {reinterpret_cast<const std::byte*>(holder->data()), holder->size() * sizeof(T)},
                   std::shared_ptr<const void>(holder, holder.get()));
    }
    /// Adds (or replaces) a section as a view of `payload` (no copy), kept valid by `keep_alive`
    /// until the writer is destroyed: a big section in a memory-mapped spill file stays out of RAM
    /// (write() streams it to the file).
    /// `file_mapped`: the payload is a file mapping (a spill file), whose pages write() drops
    /// once written (prt::drop_mapped_pages).
    void add_view(SectionType type, std::uint32_t element_size, std::uint64_t count,
                  std::span<const std::byte> payload, std::shared_ptr<const void> keep_alive,
                  bool file_mapped = false) {
        add_shared(type, element_size, count, payload, std::move(keep_alive));
        m_sections.back().file_mapped = file_mapped;
    }
    /// The bytes of a generated section: `sink` takes them front to back, in any pieces.
    using ByteSink = std::function<void(const std::byte*, std::size_t)>;
    using Generator = std::function<void(const ByteSink& sink)>;
    /// Adds (or replaces) a section whose `count` x `element_size` bytes `generate` hands to its sink
    /// when the pool is written, front to back (each write() or serialize() calls it once): a large
    /// section assembled from pieces goes to the file without first being gathered in memory or a
    /// spill file (prt-bricks' brick payloads). A generator that hands over another number of bytes
    /// is an error (nothing is written).
    void add_generated(SectionType type, std::uint32_t element_size, std::uint64_t count, Generator generate);
    /// Carries every section of `source` over as a view (no copy), except provenance, which is
    /// merged by add_provenance().
    void carry_over(const PoolFile& source);
    void remove(SectionType type);
    bool has(SectionType type) const;

    /// Appends {tool, version, parameters, time} to the provenance inherited from carry_over().
    /// `parameters_json` must be a JSON object text.
    void add_provenance(const std::string& tool, const std::string& version,
                        const std::string& parameters_json);

    /// Writes to "PATH.tmp.HOST.PID", fsyncs, renames over PATH; after the rename, removes this
    /// host's temporary files of PATH left by writers that no longer run (POOL.md "Writing"). On
    /// any failure the temporary file is removed and PATH is untouched. Returns the bytes written.
    /// The sections are streamed to the file (the pool is never assembled in memory) in one pass:
    /// each payload is hashed as it is written, and the header and table, whose checksums that
    /// gives, are written over their place at the end.
    std::uint64_t write(const std::filesystem::path& path) const;
    /// The exact bytes write() would produce (for tests and the fuzz corpus).
    std::vector<std::byte> serialize() const;

private:
    struct Pending {
        SectionType type;
        std::uint32_t element_size;
        std::uint64_t count;
        std::span<const std::byte> payload;      // empty for a generated section
        std::uint64_t size = 0;                  // payload bytes
        Generator generate;                      // a generated section's bytes, else null
        std::shared_ptr<const void> keep_alive;  // owner of payload, or null for carried views
        bool file_mapped = false;                // a file mapping: pages dropped once written
        bool checksum_known = false;             // carried: the source's checked checksum
        std::uint64_t checksum = 0;
    };
    void add_shared(SectionType type, std::uint32_t element_size, std::uint64_t count,
                    std::span<const std::byte> payload, std::shared_ptr<const void> keep_alive);
    /// Lays the file out and hands its bytes, front to back, to `sink` (the header and table as
    /// zeros), hashing each payload as it goes, then the header and table with their checksums to
    /// `rewrite_front` (the same bytes' place at offset 0); returns the file size.
    std::uint64_t emit(const ByteSink& sink, const ByteSink& rewrite_front) const;
    std::vector<Pending> m_sections;
    std::string m_provenance = "[]";
};

/// XXH3-64 of a byte range (the pool's checksum).
std::uint64_t checksum(std::span<const std::byte> bytes);
/// checksum(); when `mapped` (a file mapping), computed in 64 MiB steps whose pages are dropped
/// once hashed (prt::drop_mapped_pages): the same value, a bounded resident set.
std::uint64_t checksum_section(std::span<const std::byte> bytes, bool mapped);
/// Maps the pages of a file mapping's [data, data + bytes) in with every core (one read per 4 KiB, in
/// 2 MiB runs) before a one-thread pass reads them; ranges under 8 MiB are left to that pass.
void map_in_parallel(const std::byte* data, std::size_t bytes);

/// Sets `info`'s point_count and bounding box (bounds_min, bounds_max) from the points' positions
/// in its local frame (an empty set: min = FLT_MAX, max = -FLT_MAX).
void set_point_bounds(ModelInfo& info, std::span<const Float3> local);

/// Bytes per input point of a pool: file size / point count (prt-info, benchmarks).
double bytes_per_point(const PoolFile& pool);

}  // namespace prt::pool
