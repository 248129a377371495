// PointRT benches: one surface of one pool, traced ray by ray on the CPU through the core's own
// per-ray functions (the ones the renderer and the CUDA kernels call), for the accuracy and
// fidelity tools:
//
//   splats   closest_hit_splats (thesis 3.3 blending, 3.5 deep blending, 3.4 leaf bounds)
//   iso      trace_iso (thesis 4.5: sampling, interpolation, Illinois refinement; q8 or f32 leaves)
//   mls      trace_mls<float|double> (Wald-Seidel 2005, 3.2: k samples per cell interval)
//   patches  trace_patches (seed 002, 3: Newton in double or float)
#pragma once

#include <CLI/CLI.hpp>
#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "prt/core/iso.h"
#include "prt/core/mls.h"
#include "prt/core/patch.h"
#include "prt/core/ray.h"
#include "prt/core/splat.h"
#include "prt/formats/pool.h"
#include "prt/formats/scene_layout.h"

namespace prt::rt {
class RenderScene;
}

namespace prt::bench {

/// The settings of each surface (the accuracy knobs of issue 9; defaults are the renderer's).
struct SurfaceSettings {
    // splats
    bool deep = true;  ///< thesis 3.5, the renderer's default (RenderParams::deep_blending)
    std::uint32_t leaf_culling = 2;
    float blend_window = 1.0f;
    // iso
    std::string iso_storage = "q8";
    std::uint32_t iso_refine = 2;
    float iso_samples = 4.0f;
    // mls
    std::uint32_t mls_k = 4, mls_refine = 1;
    float mls_support_samples = core::MlsParams{}.samples_per_support;
    std::string mls_precision = "float";
    /// Both faces of the MLS surface count (prt-accuracy's measure), or the renderer's seamless
    /// rule: an outside ray accepts front faces only (thesis 3.6).
    bool mls_both_faces = false;
    // patches
    std::uint32_t patch_iterations = 16;
    double patch_tolerance = 1e-12;
    std::string patch_precision = "double";
};

/// What one ray found, in the pool's local frame.
struct ProbeHit {
    double t = 0;
    core::Vec3 normal{0, 0, 1};
    bool has_position = false;         ///< patches: the hit evaluated in double at the root
    std::array<double, 3> position{};  ///< local frame, when has_position
};

/// Declares every surface's settings on a command line (--deep-blending, --iso-samples, --mls-k,
/// --patch-precision, ...), documented with their defaults.
void add_surface_options(CLI::App& app, SurfaceSettings& s);

class SurfaceProbe {
public:
    /// Loads (and validates) the sections of `surface` ("splats", "iso", "mls", "patches"); throws
    /// prt::Error naming the pool and what is missing.
    SurfaceProbe(std::shared_ptr<const pool::PoolFile> pool, const std::string& surface,
                 const SurfaceSettings& settings);
    ~SurfaceProbe();

    /// Traces the ray (local frame); thread-safe. Returns false on a miss.
    bool trace(const core::Ray& ray, ProbeHit& hit) const;

    const std::string& surface() const { return m_surface; }
    /// The settings that apply to this surface, as JSON.
    nlohmann::json settings() const;
    /// Bytes of the sections this surface reads (leaf bounds included for splats).
    std::uint64_t bytes() const { return m_bytes; }
    /// Work per traced ray so far (splat tests, evaluations or Newton iterations), keyed by name.
    nlohmann::json work() const;
    std::uint64_t truncated() const { return m_truncated.load(); }

private:
    std::shared_ptr<const pool::PoolFile> m_pool;
    std::string m_surface;
    scene::SurfaceKind m_kind = scene::SurfaceKind::splats;  ///< m_surface parsed
    SurfaceSettings m_s;
    std::unique_ptr<rt::RenderScene> m_scene;  // splats: the renderer's leaf bounds
    const core::OctreeView* m_octree = nullptr;
    const pool::Rgba8* m_colors = nullptr;
    core::IsoView m_iso{};
    core::IsoParams m_iso_params{};
    core::MlsView m_mls{};
    core::MlsParams m_mls_params{};
    core::PatchView m_patches{};
    core::PatchTraceParams m_patch_params{};
    std::uint64_t m_bytes = 0;
    mutable std::atomic<std::uint64_t> m_rays{0}, m_work{0}, m_truncated{0};

    /// A trace's result: `h`'s distance and normal into `out` when it hit; its work and truncated
    /// walks added to the counters. Returns `hit`.
    template <class Hit>
    bool record(bool hit, const Hit& h, std::uint64_t work, std::uint64_t truncated, ProbeHit& out) const;
};

}  // namespace prt::bench
