// PointRT fuzzing (issue 10): one entry point per reader, shared by the libFuzzer targets
// (fuzz_target.cpp, built with PRT_FUZZ=ON under clang) and by the GoogleTest regression suite
// (regression_test.cpp, every build). A crash found by a fuzzer is replayed through exactly the
// function that found it.
//
// Contract of every entry: the input is fed to the reader as a user's file would be; a prt::Error
// is a clean rejection (its message must be one line naming the input); anything else the reader
// throws (std::bad_alloc, std::length_error, ...) escapes the entry, which libFuzzer reports as a
// crash and GoogleTest as a failure. Accepted inputs are checked against cheap oracles (attribute
// arrays aligned, points finite, normals unit, scene JSON round trip); a broken oracle is
// reported in Result::violation and makes the fuzz target abort.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>

namespace prt::fuzz {

/// What a reader did with one input.
struct Result {
    bool accepted = false;  ///< the reader produced a result (points, pool, scene)
    std::string message;    ///< the prt::Error message when rejected (meshes: also when accepted
                            ///< as vertices but refused for sampling; patches: also when one of
                            ///< its three readings refused it)
    std::string violation;  ///< non-empty: an oracle failed (a bug even though nothing crashed)
};

using Bytes = std::span<const std::uint8_t>;

/// The readers under test. `name` is the fuzz target's name (prt-fuzz-NAME), the folder of its
/// seed corpus (tests/fuzz/corpus/NAME) and its dictionary (tests/fuzz/dict/NAME.dict).
enum class Target {
    ply,       ///< preprocess/import: read_ply + clean (import_file, --format ply --mesh-mode points)
    pcd,       ///< our PCD header check (check_pcd), then PCL's PCDReader on files that pass it
    xyz,       ///< read_xyz + clean
    obj,       ///< mesh import of a .obj: precheck_mesh_file + OpenMesh + vertex normals / sampling
    off,       ///< the same for .off (our OFF precheck matters most here)
    ply_mesh,  ///< the same for a .ply with faces (precheck by our PLY reader, then OpenMesh's)
    scene,     ///< formats: parse_scene, then to_json/parse_scene round trip
    pool,      ///< formats: PoolFile::from_bytes (full validation), then every section read and
               ///< every on-demand validator (validate_iso, _mls, _patches, _bricks, _caustics, _light_map)
               ///< whose sections are present (message: also the first such rejection)
    patches,   ///< preprocess/patches: parse_patches with content detection (.bpt or Newell),
               ///< read_patch_file on input.bpt (the .bpt parser), parse_patches as Newell
};

struct TargetInfo {
    Target target;
    const char* name;
};

/// Every target, in the order scripts/fuzz.sh runs them.
inline constexpr TargetInfo k_targets[] = {
    {Target::ply, "ply"}, {Target::pcd, "pcd"},           {Target::xyz, "xyz"},     {Target::obj, "obj"},
    {Target::off, "off"}, {Target::ply_mesh, "ply-mesh"}, {Target::scene, "scene"}, {Target::pool, "pool"},
    {Target::patches, "patches"},
};

/// Whether this build has the library a target needs (PCL for pcd, OpenMesh for the meshes).
bool available(Target target);

/// Feeds one input to a target's reader. File-based readers get it as a file in a private scratch
/// folder (see scratch_dir()) named input.EXT, EXT being what the format needs to be recognised.
Result run(Target target, Bytes input);

/// The per-process scratch folder (under /dev/shm when it exists, else the temporary folder);
/// created on first use, removed at exit.
const std::filesystem::path& scratch_dir();

}  // namespace prt::fuzz
