#include "fuzz_entries.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstddef>
#include <cstdlib>
#include <cstring>
#include <string_view>
#include <vector>

#include "import.h"
#include "patch_file.h"
#include "point_cloud.h"
#include "prt/error.h"
#include "prt/formats/brick_sections.h"
#include "prt/formats/gi_sections.h"
#include "prt/formats/iso_sections.h"
#include "prt/formats/mls_sections.h"
#include "prt/formats/patch_sections.h"
#include "prt/formats/pool.h"
#include "prt/formats/scene.h"

namespace prt::fuzz {

namespace fs = std::filesystem;

namespace {

/// Removes the scratch folder when the process exits normally (libFuzzer's -runs=N, ctest).
struct ScratchFolder {
    fs::path path;
    ScratchFolder() {
        std::error_code ec;
        const fs::path base =
            fs::is_directory("/dev/shm", ec) ? fs::path("/dev/shm") : fs::temp_directory_path();
        path = base / ("prt-fuzz-" + std::to_string(::getpid()));
        fs::create_directories(path, ec);
        if (ec) {
            std::fprintf(stderr, "prt-fuzz: cannot create %s: %s\n", path.c_str(), ec.message().c_str());
            std::abort();
        }
    }
    ~ScratchFolder() {
        std::error_code ec;
        fs::remove_all(path, ec);
    }
};

/// Writes the input to SCRATCH/input.EXT (replacing the previous input) and returns the path.
fs::path write_input(Bytes input, const char* extension) {
    const fs::path path = scratch_dir() / (std::string("input.") + extension);
    const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
    if (fd < 0) {
        std::fprintf(stderr, "prt-fuzz: cannot write %s: %s\n", path.c_str(), std::strerror(errno));
        std::abort();
    }
    std::size_t done = 0;
    while (done < input.size()) {
        const ssize_t n = ::write(fd, input.data() + done, input.size() - done);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) {
            std::fprintf(stderr, "prt-fuzz: short write to %s\n", path.c_str());
            std::abort();
        }
        done += static_cast<std::size_t>(n);
    }
    ::close(fd);
    return path;
}

/// A rejection must be one line that names what was read (DESIGN.md: "a bad or truncated file
/// gives a one-line error naming the file ..., never a crash").
void check_message(Result& r, const std::string& label) {
    if (r.message.empty())
        r.violation = "empty error message";
    else if (r.message.find_first_of("\n\r") != std::string::npos)
        r.violation = "error message is not one line: " + r.message;
    else if (r.message.rfind(label, 0) != 0)
        r.violation = "error message does not start with the input's name '" + label + "': " + r.message;
}

/// Oracles on a point set that import_file accepted: arrays aligned, positions finite, normals
/// unit (clean() drops or renormalises every other), not empty.
std::string check_cloud(const pre::PointCloud& cloud) {
    const std::size_t n = cloud.size();
    if (n == 0) return "accepted an empty point set";
    if (cloud.has_normals() && cloud.normals.size() != n) return "normals not aligned with positions";
    if (cloud.has_colors() && cloud.colors.size() != n) return "colors not aligned with positions";
    if (cloud.has_radii() && cloud.radii.size() != n) return "radii not aligned with positions";
    for (std::size_t i = 0; i < n; ++i) {
        for (int a = 0; a < 3; ++a)
            if (!std::isfinite(cloud.positions[i][a])) return "non-finite position at " + std::to_string(i);
        if (cloud.has_normals()) {
            const auto& m = cloud.normals[i];
            const double len = std::sqrt(double(m.x) * m.x + double(m.y) * m.y + double(m.z) * m.z);
            if (!(std::fabs(len - 1.0) < 1e-3)) return "normal " + std::to_string(i) + " is not unit length";
        }
    }
    return {};
}

Result import_entry(Bytes input, const char* extension, const pre::import::Options& options) {
    const fs::path path = write_input(input, extension);
    Result r;
    try {
        pre::import::Report report;
        const pre::PointCloud cloud = pre::import::import_file(path, options, report);
        r.accepted = true;
        r.violation = check_cloud(cloud);
        if (r.violation.empty() && report.written != cloud.size())
            r.violation = "report.written disagrees with the point count";
    } catch (const Error& e) {
        r.message = e.what();
        check_message(r, path.string());
    }
    return r;
}

pre::import::Options point_options(pre::import::Format format) {
    pre::import::Options o;
    o.format = format;
    o.mesh_mode = pre::import::MeshMode::points;
    o.normals = pre::import::NormalsMode::keep;  // PCA normals are PCL's k-NN, not a reader
    o.quiet = true;
    return o;
}

Result mesh_entry(Bytes input, const char* extension) {
    pre::import::Options o;
    o.format = pre::import::Format::mesh;
    o.quiet = true;
    Result r = import_entry(input, extension, o);
    if (!r.accepted || !r.violation.empty()) return r;
    // Accepted: the same mesh sampled over its area (fan triangulation, colors, interpolated
    // normals); a mesh whose faces all have zero area is a clean rejection here too.
    o.sample = 16;
    o.sample_normals = pre::import::SampleNormals::interpolated;
    Result sampled = import_entry(input, extension, o);
    if (!sampled.violation.empty()) return sampled;
    r.message = sampled.message;  // accepted as vertices; why sampling refused it, if it did
    return r;
}

Result scene_entry(Bytes input) {
    const std::string text(reinterpret_cast<const char*>(input.data()), input.size());
    const std::string label = "fuzz.json";
    Result r;
    try {
        const scene::Scene s = scene::parse_scene(text, label, "/scenes");
        r.accepted = true;
        // SCENE.md: parse_scene(to_json(s)) gives back s exactly; compare by serialising again.
        const std::string once = scene::to_json(s);
        std::string twice;
        try {
            twice = scene::to_json(scene::parse_scene(once, label, "/scenes"));
        } catch (const Error& e) {
            r.violation = std::string("to_json output does not parse back: ") + e.what();
            return r;
        }
        if (once != twice)
            r.violation = "to_json/parse_scene round trip changed the scene:\n" + once + "\n" + twice;
    } catch (const Error& e) {
        r.message = e.what();
        check_message(r, label);
    }
    return r;
}

/// Runs formats' on-demand validators over the sections an accepted pool holds (prt/formats/
/// *_sections.h); a rejection keeps the pool accepted and becomes the result's message.
void validate_on_demand(const pool::PoolFile& file, Result& r, const std::string& label) {
    const auto attempt = [&](auto validate) {
        try {
            validate();
        } catch (const Error& e) {
            if (!r.message.empty()) return;
            r.message = e.what();
            check_message(r, label);
        }
    };
    if (pool::has_iso(file)) attempt([&] { (void)pool::validate_iso(file); });
    if (pool::has_mls(file)) attempt([&] { (void)pool::validate_mls(file); });
    if (pool::has_patches(file)) attempt([&] { (void)pool::validate_patches(file); });
    if (pool::has_bricks(file)) attempt([&] { (void)pool::validate_bricks(file); });
    attempt([&] { (void)pool::validate_caustics(file); });
    attempt([&] { (void)pool::validate_caustic_maps(file); });
    attempt([&] { (void)pool::validate_light_map(file); });
    attempt([&] { (void)pool::validate_light_maps(file); });
}

/// Validates one pool image and, when it is accepted, reads it through every accessor the tools use.
Result pool_image(std::vector<std::byte> bytes, const std::string& label) {
    Result r;
    try {
        const pool::PoolFile file = pool::PoolFile::from_bytes(std::move(bytes), label);
        r.accepted = true;
        const pool::ModelInfo& info = file.model_info();
        (void)file.provenance_json();
        std::uint64_t touched = 0;
        for (const pool::SectionEntry& e : file.sections())
            for (const std::byte b : file.bytes(e)) touched += static_cast<std::uint8_t>(b);
        (void)touched;
        if (info.point_count > 0) {
            const pre::PointCloud cloud = pre::read_point_sections(file);
            if (cloud.size() != info.point_count) r.violation = "positions disagree with model_info";
        }
        const auto nodes = file.array<std::uint32_t>(pool::SectionType::octree_nodes);
        const auto leaves = file.array<std::uint32_t>(pool::SectionType::leaf_info);
        const auto splats = file.array<pool::Splat>(pool::SectionType::splats);
        // Walk the octree as the runtime would: every filled leaf's splat range inside the splats.
        for (const std::uint32_t n : nodes)
            if (pool::node_type(n) == pool::NodeType::filled_leaf) {
                const std::uint32_t a = pool::node_address(n);
                if (a + 1 >= leaves.size() || leaves[a] > leaves[a + 1] || leaves[a + 1] > splats.size())
                    r.violation = "a filled leaf addresses splats outside the splat section";
            }
        // The sections validated on demand (a renderer asking for that surface or map): their
        // rejections are clean one-line errors too; the first one is the entry's message.
        validate_on_demand(file, r, label);
    } catch (const Error& e) {
        r.message = e.what();
        check_message(r, label);
    }
    return r;
}

/// Recomputes every checksum of a pool image that has a header (payloads inside the file, then
/// the table, then the header), so mutations reach the structural checks behind the checksums.
/// Returns false when there is nothing to repair.
bool repair_checksums(std::vector<std::byte>& bytes) {
    if (bytes.size() < sizeof(pool::PoolHeader)) return false;
    pool::PoolHeader h;
    std::memcpy(&h, bytes.data(), sizeof h);
    const std::uint64_t size = bytes.size();
    const std::uint64_t table_bytes = std::uint64_t(h.section_count) * sizeof(pool::SectionEntry);
    if (h.section_count <= pool::k_max_sections && h.table_offset <= size &&
        table_bytes <= size - h.table_offset) {
        for (std::uint32_t i = 0; i < h.section_count; ++i) {
            pool::SectionEntry e;
            std::byte* at = bytes.data() + h.table_offset + i * sizeof(pool::SectionEntry);
            std::memcpy(&e, at, sizeof e);
            if (e.offset > size || e.size > size - e.offset) continue;
            e.checksum = pool::checksum({bytes.data() + e.offset, static_cast<std::size_t>(e.size)});
            std::memcpy(at, &e, sizeof e);
        }
        h.table_checksum =
            pool::checksum({bytes.data() + h.table_offset, static_cast<std::size_t>(table_bytes)});
    }
    std::memcpy(bytes.data(), &h, sizeof h);
    h.header_checksum = pool::checksum({bytes.data(), offsetof(pool::PoolHeader, header_checksum)});
    std::memcpy(bytes.data(), &h, sizeof h);
    return true;
}

/// The image as given (checksums must reject corruption), then with its checksums repaired (so
/// the fuzzer explores the structural checks: bounds, counts, cross-references).
Result pool_entry(Bytes input) {
    std::vector<std::byte> bytes(input.size());
    if (!input.empty()) std::memcpy(bytes.data(), input.data(), input.size());
    Result raw = pool_image(bytes, "fuzz.pool");
    if (!raw.violation.empty()) return raw;
    if (!repair_checksums(bytes)) return raw;
    Result repaired = pool_image(std::move(bytes), "fuzz.pool");
    if (!repaired.violation.empty()) return repaired;
    raw.accepted = raw.accepted || repaired.accepted;
    return raw;
}

// ---- Bezier patch files ----------------------------------------------------------------------

/// Appends a double in its shortest form that reads back to the same bits (std::to_chars).
void put_number(std::string& out, double v) {
    char buf[32];
    const auto r = std::to_chars(buf, buf + sizeof buf, v);
    out.append(buf, r.ptr);
}

/// Accepted nets written back as a patch file of `format` (.bpt: count, "3 3", 16 points per
/// patch; Newell: every patch with its own 16 vertices), numbers in shortest round-trip form.
std::string patch_text(const std::vector<pool::PatchControlNet>& nets, patches::PatchFormat format) {
    std::string s = std::to_string(nets.size()) + "\n";
    const bool bpt = format == patches::PatchFormat::bpt;
    if (!bpt)
        for (std::size_t p = 0; p < nets.size(); ++p)
            for (int k = 0; k < 16; ++k) s += std::to_string(16 * p + k + 1) + (k == 15 ? "\n" : ",");
    if (!bpt) s += std::to_string(16 * nets.size()) + "\n";
    for (const pool::PatchControlNet& net : nets) {
        if (bpt) s += "3 3\n";
        for (const pool::PatchPoint& q : net.p) {
            put_number(s, q.x);
            s += bpt ? ' ' : ',';
            put_number(s, q.y);
            s += bpt ? ' ' : ',';
            put_number(s, q.z);
            s += '\n';
        }
    }
    return s;
}

/// Oracles on a patch set a reader accepted: at least one and at most pool::k_max_patches nets,
/// the format it says it read, finite control points, and writing the nets back as .bpt and as
/// Newell text reads back (by content detection) to the same format and the same bits.
std::string check_patches(const patches::PatchSet& set, patches::PatchFormat expected) {
    using patches::PatchFormat;
    if (set.nets.empty()) return "accepted a file without patches";
    if (set.nets.size() > pool::k_max_patches) return "accepted more patches than pool::k_max_patches";
    const bool format_ok =
        expected == PatchFormat::automatic ? set.format != PatchFormat::automatic : set.format == expected;
    if (!format_ok) return std::string("read as ") + patches::patch_format_name(set.format);
    for (const pool::PatchControlNet& net : set.nets)
        for (const pool::PatchPoint& q : net.p)
            if (!std::isfinite(q.x) || !std::isfinite(q.y) || !std::isfinite(q.z))
                return "non-finite control point";
    for (const PatchFormat format : {PatchFormat::bpt, PatchFormat::newell}) {
        const std::string text = patch_text(set.nets, format);
        patches::PatchSet back;
        try {
            back = patches::parse_patches(text, "round-trip", PatchFormat::automatic);
        } catch (const Error& e) {
            return std::string("written back as ") + patches::patch_format_name(format) +
                   " it does not parse: " + e.what();
        }
        if (back.format != format)
            return std::string("written back as ") + patches::patch_format_name(format) +
                   " it is detected as " + patches::patch_format_name(back.format);
        if (back.nets.size() != set.nets.size() ||
            std::memcmp(back.nets.data(), set.nets.data(), set.nets.size() * sizeof(pool::PatchControlNet)) !=
                0)
            return std::string("written back as ") + patches::patch_format_name(format) + " the nets changed";
    }
    return {};
}

/// One reading of a patch input; folds its outcome into `r` (the first rejection's message is
/// kept, any acceptance counts, the first oracle violation wins).
template <class Read>
void patch_attempt(Result& r, Read read, const std::string& label, patches::PatchFormat expected) {
    Result one;
    try {
        const patches::PatchSet set = read();
        one.accepted = true;
        one.violation = check_patches(set, expected);
    } catch (const Error& e) {
        one.message = e.what();
        check_message(one, label);
    }
    r.accepted = r.accepted || one.accepted;
    if (r.message.empty()) r.message = one.message;
    if (r.violation.empty() && !one.violation.empty())
        r.violation = patches::patch_format_name(expected) + std::string(" reading: ") + one.violation;
}

/// The input's text through parse_patches with content detection (what prt-patches does with a
/// file not named .bpt; its rejection is the entry's message), then through read_patch_file as
/// input.bpt (the extension selects the .bpt parser), then parsed as Newell.
Result patch_entry(Bytes input) {
    using patches::PatchFormat;
    const std::string text(reinterpret_cast<const char*>(input.data()), input.size());
    const std::string label = "fuzz.patches";
    Result r;
    patch_attempt(
        r, [&] { return patches::parse_patches(text, label, PatchFormat::automatic); }, label,
        PatchFormat::automatic);
    const fs::path path = write_input(input, "bpt");
    patch_attempt(
        r, [&] { return patches::read_patch_file(path, PatchFormat::automatic); }, path.string(),
        PatchFormat::bpt);
    patch_attempt(
        r, [&] { return patches::parse_patches(text, label, PatchFormat::newell); }, label,
        PatchFormat::newell);
    return r;
}

}  // namespace

const fs::path& scratch_dir() {
    static const ScratchFolder folder;
    return folder.path;
}

bool available(Target target) {
    switch (target) {
        case Target::pcd:
            return pre::import::have_pcl();
        case Target::obj:
        case Target::off:
        case Target::ply_mesh:
            return pre::import::have_openmesh();
        default:
            return true;
    }
}

Result run(Target target, Bytes input) {
    using pre::import::Format;
    switch (target) {
        case Target::ply:
            return import_entry(input, "ply", point_options(Format::ply));
        case Target::pcd:
            return import_entry(input, "pcd", point_options(Format::pcd));
        case Target::xyz:
            return import_entry(input, "xyz", point_options(Format::xyz));
        case Target::obj:
            return mesh_entry(input, "obj");
        case Target::off:
            return mesh_entry(input, "off");
        case Target::ply_mesh:
            return mesh_entry(input, "ply");
        case Target::scene:
            return scene_entry(input);
        case Target::pool:
            return pool_entry(input);
        case Target::patches:
            return patch_entry(input);
    }
    return {};
}

}  // namespace prt::fuzz
