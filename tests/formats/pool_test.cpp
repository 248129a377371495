// Pool file: round trips and every validation error of formats/POOL.md.
#include "prt/formats/pool.h"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <vector>

#include "point_cloud.h"
#include "prt/atomic_file.h"
#include "prt/formats/section_table.h"

namespace fs = std::filesystem;
using namespace prt::pool;

namespace {

fs::path temp_dir() {
    const fs::path dir = fs::temp_directory_path() / ("prt_pool_test_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    return dir;
}

prt::pre::PointCloud make_cloud(std::size_t n, double offset = 0.0) {
    prt::pre::PointCloud c;
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (std::size_t i = 0; i < n; ++i) {
        c.positions.push_back({offset + u(rng), offset + u(rng), offset + u(rng)});
        c.normals.push_back({0.f, 0.f, 1.f});
        c.colors.push_back({std::uint8_t(i), 2, 3, 255});
    }
    return c;
}

std::vector<std::byte> make_pool_bytes(std::size_t n = 100) {
    PoolWriter w;
    prt::pre::write_point_sections(make_cloud(n), w);
    w.add_provenance("pool_test", "0", R"({"n": 100})");
    return w.serialize();
}

/// Re-seals a mutated image: recomputes payload, table and header checksums, so the check under
/// test (not a checksum) is what fires.
void reseal(std::vector<std::byte>& bytes) {
    auto* h = reinterpret_cast<PoolHeader*>(bytes.data());
    auto* table = reinterpret_cast<SectionEntry*>(bytes.data() + h->table_offset);
    for (std::uint32_t i = 0; i < h->section_count; ++i)
        if (table[i].offset + table[i].size <= bytes.size())
            table[i].checksum =
                checksum({bytes.data() + table[i].offset, static_cast<std::size_t>(table[i].size)});
    h->table_checksum =
        checksum({reinterpret_cast<const std::byte*>(table), h->section_count * sizeof(SectionEntry)});
    h->header_checksum = checksum({bytes.data(), offsetof(PoolHeader, header_checksum)});
}

SectionEntry& entry_of(std::vector<std::byte>& bytes, SectionType type) {
    auto* h = reinterpret_cast<PoolHeader*>(bytes.data());
    auto* table = reinterpret_cast<SectionEntry*>(bytes.data() + h->table_offset);
    for (std::uint32_t i = 0; i < h->section_count; ++i)
        if (table[i].type == static_cast<std::uint32_t>(type)) return table[i];
    throw std::runtime_error("no such section");
}

std::string open_error(std::vector<std::byte> bytes) {
    try {
        PoolFile::from_bytes(std::move(bytes), "bad.pool");
    } catch (const prt::Error& e) {
        return e.what();
    }
    return "";
}

void expect_error(std::vector<std::byte> bytes, const std::string& must_contain) {
    const std::string msg = open_error(std::move(bytes));
    ASSERT_FALSE(msg.empty()) << "expected an error containing '" << must_contain << "'";
    EXPECT_NE(msg.find("bad.pool"), std::string::npos) << msg;
    EXPECT_NE(msg.find(must_contain), std::string::npos) << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << "one line: " << msg;
}

}  // namespace

TEST(Pool, RoundTripKeepsEverySection) {
    const auto cloud = make_cloud(1000, 1e6);
    PoolWriter w;
    prt::pre::write_point_sections(cloud, w);
    w.add_provenance("pool_test", "1.2", R"({"k": 9})");
    const fs::path path = temp_dir() / "round.pool";
    const std::uint64_t written = w.write(path);
    EXPECT_EQ(written, fs::file_size(path));

    const PoolFile pool = PoolFile::open(path);
    EXPECT_EQ(pool.model_info().point_count, 1000u);
    const auto back = prt::pre::read_point_sections(pool);
    ASSERT_EQ(back.size(), cloud.size());
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        for (int a = 0; a < 3; ++a)  // float offsets from a double origin: relative to the model size
            EXPECT_NEAR(back.positions[i][a], cloud.positions[i][a], 1e-6);
        EXPECT_EQ(back.colors[i].r, cloud.colors[i].r);
        EXPECT_EQ(back.normals[i].z, 1.f);
    }
    for (const SectionEntry& e : pool.sections()) {
        EXPECT_EQ(e.offset % k_alignment, 0u) << e.name;
        EXPECT_EQ(e.version, section_version(static_cast<SectionType>(e.type)));
    }
    EXPECT_NE(pool.provenance_json().find("\"pool_test\""), std::string::npos);
    EXPECT_NE(pool.provenance_json().find("\"k\":9"), std::string::npos);
    EXPECT_GT(bytes_per_point(pool), 28.0);  // 12 position + 12 normal + 4 color + overhead
}

TEST(Pool, CarryOverKeepsSectionsAndAppendsProvenance) {
    const fs::path dir = temp_dir();
    PoolWriter first;
    prt::pre::write_point_sections(make_cloud(50), first);
    first.add_provenance("step1", "1", "{}");
    first.write(dir / "a.pool");
    {
        const PoolFile a = PoolFile::open(dir / "a.pool");
        PoolWriter second;
        second.carry_over(a);
        second.add_array(SectionType::radii, std::vector<float>(50, 0.25f));
        second.add_provenance("step2", "1", R"({"k": 9})");
        second.write(dir / "a.pool");  // in place: the mapped source stays valid until rename
    }
    const PoolFile b = PoolFile::open(dir / "a.pool");
    EXPECT_EQ(b.array<float>(SectionType::radii).size(), 50u);
    EXPECT_EQ(b.array<Float3>(SectionType::positions).size(), 50u);
    const std::string prov = b.provenance_json();
    EXPECT_LT(prov.find("step1"), prov.find("step2"));
}

TEST(Pool, SerializationIsDeterministicApartFromTime) {
    PoolWriter w;
    prt::pre::write_point_sections(make_cloud(10), w);
    EXPECT_EQ(w.serialize(), w.serialize());
}

TEST(PoolValidation, ValidImageOpens) {
    EXPECT_EQ(open_error(make_pool_bytes()), "");
}

TEST(PoolValidation, WrongMagic) {
    auto b = make_pool_bytes();
    b[0] = std::byte{'X'};
    expect_error(b, "wrong magic");
}

TEST(PoolValidation, NewerFormatVersion) {
    auto b = make_pool_bytes();
    reinterpret_cast<PoolHeader*>(b.data())->format_major = k_format_major + 1;
    reseal(b);
    expect_error(b, "newer than this build");
}

TEST(PoolValidation, NewerSectionVersion) {
    auto b = make_pool_bytes();
    entry_of(b, SectionType::normals).version = 99;
    reseal(b);
    expect_error(b, "section normals: version 99 is newer");
}

TEST(PoolValidation, TruncatedFile) {
    auto b = make_pool_bytes();
    b.resize(b.size() - 300);
    expect_error(b, "truncated");
    b.resize(20);
    expect_error(b, "too short");
}

TEST(PoolValidation, SectionOutOfBounds) {
    auto b = make_pool_bytes();
    entry_of(b, SectionType::colors).offset = (b.size() + 4096) / k_alignment * k_alignment;
    reseal(b);
    expect_error(b, "section colors: payload");
}

TEST(PoolValidation, HugeClaimsAreRejectedBeforeAllocation) {
    auto b = make_pool_bytes();
    // 10^15 points claimed: sizes disagree with the file long before anything is allocated
    SectionEntry& e = entry_of(b, SectionType::positions);
    e.count = 1000000000000000ull;
    e.size = e.count * sizeof(Float3);
    reseal(b);
    expect_error(b, "section positions: payload");
    auto c = make_pool_bytes();
    auto* h = reinterpret_cast<PoolHeader*>(c.data());
    h->section_count = 1u << 30;
    h->header_checksum = checksum({c.data(), offsetof(PoolHeader, header_checksum)});
    expect_error(c, "exceeds the limit");
}

TEST(PoolValidation, BadPayloadChecksum) {
    auto b = make_pool_bytes();
    const SectionEntry& e = entry_of(b, SectionType::positions);
    b[e.offset + 5] ^= std::byte{0x40};
    expect_error(b, "section positions: bad checksum");
}

// A mapped file's sections are checked in 64 MiB steps, each mapped in by every core first
// (pool_reader.cpp): a section of more than one step reads back, and a byte flipped in its last
// step (or in its first) is found.
TEST(PoolValidation, LargeMappedSectionIsCheckedInEveryStep) {
    const std::size_t n = 5'800'000;  // positions: 69.6 MB, more than one 64 MiB step
    const fs::path path = temp_dir() / "large.pool";
    {
        PoolWriter w;
        prt::pre::write_point_sections(make_cloud(n), w);
        w.write(path);
    }
    SectionEntry e{};
    {
        const PoolFile pool = PoolFile::open(path);
        ASSERT_EQ(pool.array<Float3>(SectionType::positions).size(), n);
        for (const SectionEntry& s : pool.sections())
            if (s.type == static_cast<std::uint32_t>(SectionType::positions)) e = s;
    }
    ASSERT_GT(e.size, std::uint64_t{64} << 20);
    for (const std::uint64_t at : {e.offset + e.size - 3, e.offset + 4096 + 1}) {
        auto flip = [&] {
            std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
            f.seekg(static_cast<std::streamoff>(at));
            char c = 0;
            f.read(&c, 1);
            c = static_cast<char>(c ^ 0x10);
            f.seekp(static_cast<std::streamoff>(at));
            f.write(&c, 1);
        };
        flip();
        try {
            (void)PoolFile::open(path);
            ADD_FAILURE() << "a flipped byte at " << at << " was not found";
        } catch (const prt::Error& err) {
            EXPECT_NE(std::string(err.what()).find("section positions: bad checksum"), std::string::npos)
                << err.what();
        }
        flip();  // back: the file is valid again
        EXPECT_NO_THROW((void)PoolFile::open(path));
    }
    fs::remove(path);
}

TEST(PoolValidation, BadHeaderChecksum) {
    auto b = make_pool_bytes();
    reinterpret_cast<PoolHeader*>(b.data())->flags = 7;
    expect_error(b, "header: bad checksum");
}

TEST(PoolValidation, CountsDisagree) {
    auto b = make_pool_bytes();
    // model_info says 100 points; shrink colors to 99 elements
    SectionEntry& e = entry_of(b, SectionType::colors);
    e.count = 99;
    e.size = 99 * sizeof(Rgba8);
    reseal(b);
    expect_error(b, "section colors: 99 elements but model_info says 100");
}

TEST(PoolValidation, ElementSizeMismatch) {
    auto b = make_pool_bytes();
    SectionEntry& e = entry_of(b, SectionType::colors);
    e.element_size = 2;
    e.count = 200;
    reseal(b);
    expect_error(b, "section colors: element size 2, expected 4");
}

TEST(PoolValidation, SurfaceSectionElementSizeIsCheckedAtOpen) {
    // Every type of the section table has its element size checked by open(), not only the point
    // and octree types: an iso_info of 4-byte elements (IsoInfo is 64 bytes, POOL.md) is refused.
    PoolWriter w;
    prt::pre::write_point_sections(make_cloud(10), w);
    w.add_array(SectionType::iso_info, std::vector<std::uint32_t>(16, 0u));
    expect_error(w.serialize(), "section iso_info: element size 4, expected 64");
}

TEST(SectionTable, RowsAgreeWithPoolMd) {
    // Names and element sizes of formats/POOL.md's "Section types" table (types 1-19) and of the
    // ISO, MLS, light-map and patch info structs (their sections of POOL.md).
    struct Row {
        std::uint32_t type;
        const char* name;
        std::uint32_t element_size;
    };
    const Row rows[] = {{1, "provenance", 1},   {2, "model_info", 64},   {3, "positions", 12},
                        {4, "normals", 12},     {5, "colors", 4},        {6, "radii", 4},
                        {7, "material_ids", 4}, {8, "intensities", 4},   {9, "sensors", 32},
                        {10, "scan_ids", 2},    {16, "octree_info", 64}, {17, "octree_nodes", 4},
                        {18, "leaf_info", 4},   {19, "splats", 32},      {32, "iso_info", 64},
                        {33, "iso_nodes", 4},   {50, "mls_refs", 4},     {81, "light_map_nodes", 4},
                        {112, "patch_info", 64}};
    for (const Row& r : rows) {
        const auto type = static_cast<SectionType>(r.type);
        EXPECT_STREQ(section_name(type), r.name) << r.type;
        EXPECT_EQ(section_element_size(type), r.element_size) << r.name;
        EXPECT_EQ(section_version(type), 1u) << r.name;
    }
    // One element per point: exactly the seven sections POOL.md's validation step 3 names.
    std::vector<std::string> per_point;
    for (const SectionTypeInfo& row : k_section_types)
        if (row.per_point) per_point.push_back(row.name);
    EXPECT_EQ(per_point, (std::vector<std::string>{"positions", "normals", "colors", "radii", "material_ids",
                                                   "intensities", "scan_ids"}));
    // Every name once; types the build does not know have none.
    for (const SectionTypeInfo& a : k_section_types)
        for (const SectionTypeInfo& b : k_section_types)
            if (&a != &b) EXPECT_STRNE(a.name, b.name);
    EXPECT_STREQ(section_name(static_cast<SectionType>(20)), "unknown");
    EXPECT_EQ(section_element_size(static_cast<SectionType>(96)), 0u);
    EXPECT_EQ(section_type_info(static_cast<SectionType>(999)), nullptr);
}

namespace {
std::vector<std::byte> make_octree_pool(std::vector<std::uint32_t> nodes, std::vector<std::uint32_t> leaves,
                                        std::vector<Splat> splats) {
    PoolWriter w;
    prt::pre::write_point_sections(make_cloud(4), w);
    OctreeInfo info{};
    info.root_size = 2.f;
    info.root_min[0] = info.root_min[1] = info.root_min[2] = -1.f;
    info.node_count = static_cast<std::uint32_t>(nodes.size());
    info.filled_leaves = static_cast<std::uint32_t>(leaves.size() - 1);
    info.splat_count = splats.size();
    info.unique_splats = splats.size();
    w.add_array(SectionType::octree_info, std::vector<OctreeInfo>{info});
    w.add_array(SectionType::octree_nodes, std::move(nodes));
    w.add_array(SectionType::leaf_info, std::move(leaves));
    w.add_array(SectionType::splats, std::move(splats));
    return w.serialize();
}
std::vector<std::uint32_t> root_with_leaves() {
    std::vector<std::uint32_t> nodes{make_node(NodeType::internal, 1)};
    for (int c = 0; c < 8; ++c)
        nodes.push_back(c == 0 ? make_node(NodeType::filled_leaf, 0) : make_node(NodeType::empty_leaf, 0));
    return nodes;
}
}  // namespace

TEST(PoolValidation, OctreeCrossReferences) {
    const Splat s{{0, 0, 0}, 0.1f, {0, 0, 1}, 0};
    EXPECT_EQ(open_error(make_octree_pool(root_with_leaves(), {0, 2}, {s, s})), "");

    auto child_out = root_with_leaves();
    child_out[0] = make_node(NodeType::internal, 5);  // children 5..12 but only 9 nodes
    expect_error(make_octree_pool(child_out, {0, 2}, {s, s}),
                 "section octree_nodes: node 0: child address 5");

    auto leaf_out = root_with_leaves();
    leaf_out[1] = make_node(NodeType::filled_leaf, 3);
    expect_error(make_octree_pool(leaf_out, {0, 2}, {s, s}), "node 1: leaf address 3 out of range");

    expect_error(make_octree_pool(root_with_leaves(), {0, 3}, {s, s}), "section leaf_info: leaf ranges");

    Splat bad = s;
    bad.point = 4;  // 4 points in the model
    expect_error(make_octree_pool(root_with_leaves(), {0, 2}, {s, bad}),
                 "splat 1: point index 4 out of range");

    auto type3 = root_with_leaves();
    type3[2] = 3u << 30;
    expect_error(make_octree_pool(type3, {0, 2}, {s, s}), "invalid node type");
}

namespace {
std::vector<std::byte> make_scan_pool(std::vector<Sensor> sensors, std::vector<std::uint16_t> ids) {
    auto cloud = make_cloud(4);
    cloud.sensors = std::move(sensors);
    cloud.scan_ids = std::move(ids);
    cloud.intensities = {0.5f, 1.f, 2.f, 3.f};
    PoolWriter w;
    prt::pre::write_point_sections(cloud, w);
    return w.serialize();
}
}  // namespace

TEST(PoolValidation, SensorsAndScanIds) {
    const Sensor at{{1, 2, 3}, k_sensor_point, 0}, far{{0, 0, 1}, k_sensor_direction, 0};
    EXPECT_EQ(open_error(make_scan_pool({at, far}, {0, 1, 1, 0})), "");
    {  // the point sections come back, intensities and sensors included
        const PoolFile p = PoolFile::from_bytes(make_scan_pool({at, far}, {0, 1, 1, 0}), "ok.pool");
        const auto back = prt::pre::read_point_sections(p);
        ASSERT_EQ(back.sensors.size(), 2u);
        EXPECT_EQ(back.sensors[1].kind, k_sensor_direction);
        EXPECT_EQ(back.scan_ids, (std::vector<std::uint16_t>{0, 1, 1, 0}));
        EXPECT_EQ(back.intensities, (std::vector<float>{0.5f, 1.f, 2.f, 3.f}));
    }
    expect_error(make_scan_pool({at}, {0, 1, 0, 0}), "section scan_ids: point 1: scan 1 but 1 sensors");
    expect_error(make_scan_pool({}, {0, 0, 0, 0}), "section scan_ids: scan_ids without a sensors section");
    Sensor bad_kind = at;
    bad_kind.kind = 7;
    expect_error(make_scan_pool({bad_kind}, {}), "section sensors: sensor 0: unknown kind 7");
    Sensor not_unit = far;
    not_unit.position[2] = 2;
    expect_error(make_scan_pool({at, not_unit}, {}),
                 "section sensors: sensor 1: direction not of unit length");
    Sensor nan = at;
    nan.position[0] = std::nan("");
    expect_error(make_scan_pool({nan}, {}), "section sensors: sensor 0: position not finite");
    auto short_ids = make_scan_pool({at}, {0, 0, 0, 0});
    SectionEntry& e = entry_of(short_ids, SectionType::scan_ids);
    e.count = 3;
    e.size = 6;
    reseal(short_ids);
    expect_error(short_ids, "section scan_ids: 3 elements but model_info says 4");
}

TEST(PoolValidation, MissingRequiredSectionNamesIt) {
    const PoolFile pool = PoolFile::from_bytes(make_pool_bytes(), "m.pool");
    try {
        pool.require<float>(SectionType::radii, "prt-octree");
        FAIL();
    } catch (const prt::Error& e) {
        EXPECT_STREQ(e.what(), "m.pool: section radii: missing (needed by prt-octree)");
    }
}

TEST(PoolValidation, EveryByteFlipIsCaughtOrHarmless) {
    // A crude in-test fuzz: flipping any byte either leaves a valid pool (padding) or gives a
    // prt::Error; never a crash.
    const auto good = make_pool_bytes(20);
    for (std::size_t i = 0; i < good.size(); i += 7) {
        auto b = good;
        b[i] ^= std::byte{0xff};
        try {
            PoolFile::from_bytes(std::move(b), "flip.pool");
        } catch (const prt::Error&) {
        }
    }
}

TEST(PoolWrite, FailedWriteLeavesPreviousFileIntact) {
    const fs::path dir = temp_dir();
    const fs::path path = dir / "keep.pool";
    PoolWriter w;
    prt::pre::write_point_sections(make_cloud(30), w);
    w.write(path);
    const auto before = fs::file_size(path);
    // Writing into a folder that does not exist fails with a message, and nothing else changes.
    EXPECT_THROW(w.write(dir / "missing" / "x.pool"), prt::Error);
    EXPECT_EQ(fs::file_size(path), before);
    for (const auto& entry : fs::directory_iterator(dir))
        EXPECT_EQ(entry.path().string().find(".tmp."), std::string::npos) << entry.path();
}

TEST(AtomicFile, LargeFileInUnevenPiecesIsWrittenWhole) {
    // The write-back is started every 8 MB while writing (sync_file_range): pieces below, across
    // and far above that size, in order, must give the file byte for byte.
    const fs::path dir = temp_dir();
    const fs::path path = dir / "big.bin";
    std::vector<unsigned char> bytes(27u << 20);
    std::mt19937 rng(7);
    for (auto& b : bytes) b = static_cast<unsigned char>(rng());
    {
        prt::AtomicFile f(path);
        std::size_t at = 0;
        for (std::size_t piece : {std::size_t{1}, std::size_t{(9u << 20) + 3}, std::size_t{4096},
                                  std::size_t{(3u << 20) - 1}, std::size_t{0}}) {
            f.write(bytes.data() + at, piece);
            at += piece;
        }
        f.write(bytes.data() + at, bytes.size() - at);  // the rest: over 14 MB at once
        EXPECT_FALSE(fs::exists(path)) << "visible before commit";
        f.commit();
    }
    ASSERT_EQ(fs::file_size(path), bytes.size());
    std::ifstream in(path, std::ios::binary);
    std::vector<unsigned char> back(bytes.size());
    in.read(reinterpret_cast<char*>(back.data()), static_cast<std::streamsize>(back.size()));
    EXPECT_TRUE(back == bytes);
    for (const auto& entry : fs::directory_iterator(dir))
        EXPECT_EQ(entry.path().string().find(".tmp."), std::string::npos) << entry.path();
}

TEST(PoolWrite, KilledWriterLeavesPreviousPoolIntact) {
    // A writer killed with SIGKILL mid-write leaves the old pool valid and no file at the target
    // other than it (the temporary file is the only partial output).
    const fs::path dir = temp_dir();
    const fs::path path = dir / "killed.pool";
    PoolWriter small;
    prt::pre::write_point_sections(make_cloud(10), small);
    small.write(path);
    const auto before = fs::file_size(path);
    const pid_t child = ::fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
        PoolWriter big;
        prt::pre::write_point_sections(make_cloud(3000000), big);
        for (;;) big.write(path);  // rewrite forever until killed
    }
    ::usleep(1500 * 1000);
    ::kill(child, SIGKILL);
    int status = 0;
    ::waitpid(child, &status, 0);
    const PoolFile pool = PoolFile::open(path);  // valid: either the old or a complete new pool
    const auto n = pool.model_info().point_count;
    EXPECT_TRUE(n == 10 || n == 3000000) << n;
    if (n == 10) {
        EXPECT_EQ(fs::file_size(path), before);
    }
    // The killed writer's temporary file (when it died mid-write) goes with the next write to that
    // path, which removes this host's dead writers' temporaries; none is left in the folder.
    small.write(path);
    for (const auto& entry : fs::directory_iterator(dir))
        EXPECT_EQ(entry.path().string().find(".tmp."), std::string::npos) << entry.path();
}

TEST(PointCloud, CleanCountsWhatItDrops) {
    prt::pre::PointCloud c;
    const double nan = std::numeric_limits<double>::quiet_NaN();
    c.positions = {{0, 0, 0}, {nan, 0, 0}, {1, 1, 1}, {0, 0, 0}, {2, 2, 2}, {3, 3, 3}};
    c.normals = {{0, 0, 2}, {0, 0, 1}, {0, 0, 0},
                 {0, 1, 0}, {1, 0, 0}, {0, 0, std::numeric_limits<float>::infinity()}};
    const auto r = prt::pre::clean(c);
    EXPECT_EQ(r.input, 6u);
    EXPECT_EQ(r.non_finite, 1u);
    EXPECT_EQ(r.zero_normal, 2u);
    EXPECT_EQ(r.duplicates, 1u);
    EXPECT_EQ(r.kept, 2u);
    ASSERT_EQ(c.size(), 2u);
    EXPECT_FLOAT_EQ(c.normals[0].z, 1.f);  // renormalised, first of the duplicates kept
    EXPECT_EQ(c.positions[1][0], 2.0);
}

TEST(PointCloud, EmptyCloudIsAnError) {
    PoolWriter w;
    EXPECT_THROW(prt::pre::write_point_sections({}, w), prt::Error);
}

TEST(PrtInfo, PrintsSectionsAndFailsOnBadFiles) {
    const fs::path dir = temp_dir();
    PoolWriter w;
    prt::pre::write_point_sections(make_cloud(64), w);
    w.add_provenance("pool_test", "1", "{}");
    w.write(dir / "info.pool");
    const std::string bin = std::string(PRT_BIN_DIR) + "/prt-info";
    const std::string out = (dir / "info.txt").string();
    ASSERT_EQ(std::system((bin + " " + (dir / "info.pool").string() + " > " + out).c_str()), 0);
    std::ifstream in(out);
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_NE(text.find("points: 64"), std::string::npos) << text;
    EXPECT_NE(text.find("positions"), std::string::npos);
    EXPECT_NE(text.find("pool_test"), std::string::npos);

    std::ofstream(dir / "junk.pool")
        << "this is not a pool file at all, but it is longer than a header......";
    const int rc = std::system((bin + " " + (dir / "junk.pool").string() + " 2> " + out).c_str());
    EXPECT_EQ(WEXITSTATUS(rc), 1);
    std::ifstream err(out);
    std::string line;
    std::getline(err, line);
    EXPECT_NE(line.find("junk.pool"), std::string::npos) << line;
    EXPECT_NE(line.find("wrong magic"), std::string::npos) << line;
    EXPECT_EQ(WEXITSTATUS(std::system((bin + " 2>/dev/null").c_str())), 2);  // usage error
}
