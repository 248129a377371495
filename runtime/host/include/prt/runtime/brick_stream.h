// PointRT runtime (host): streaming a bricked pool's bricks (issue 17; formats/POOL.md "Bricks and
// level of detail") under a memory budget, the same policy for every backend.
//
// Always resident: the top tree, the brick table, the LOD discs and four per-brick tables (the
// resident table, each brick's first leaf bound, the use and request flags), and the bricks' LOD
// prefixes when the budget holds them (at most half of each model's arena and prefixes; else
// they stream, with two more per-brick tables: where each prefix is, its use flag). The rest of the
// budget is an arena of 64-byte granules; a resident brick takes one block of it: its payload (copied
// as opaque bytes: table[b].offset, table[b].size) and its leaf bounds (computed at upload from that
// brick alone); a streamed prefix another (its node words, then its discs), resident whenever its
// payload is. A ray reaching a brick whose prefix is missing meets the brick's top-node disc and asks
// for it (the prefix is uploaded first, then, if the ray's stop lies below it, the payload). A ray that
// reaches a brick that is not resident uses its LOD disc and flags it (core bricks.h stopped_at_disc: the
// first such brick on its way only); rays that need a resident one's payload flag it used (not past a missing
// one). After each frame: the flags are read, the requested bricks are checked by their own checksum
// (pool::validate_brick) and uploaded, at most StreamOptions::upload_per_frame bytes per frame and until the
// frame has taken StreamOptions::frame_seconds, each into the first free block that fits (first fit, free
// blocks merged), evicting bricks the frame did not use, least recently used first, until one fits; then the
// resident table is updated for the next frame. When the whole scene fits the budget, every brick is loaded
// as without streaming (in core).
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "prt/core/bricks.h"
#include "prt/runtime/backend.h"
#include "prt/runtime/render_scene.h"

namespace prt::rt {

/// The shape of one model's brick arena.
struct BrickArena {
    std::uint32_t brick_count = 0;
    std::uint64_t bytes = 0;  ///< the arena (payloads and their leaf bounds), a multiple of 64
    /// LOD prefixes streamed into the arena too (a block each: its node words, then its discs),
    /// with the prefix_first and prefix_used tables; false: every prefix resident in the scene.
    bool streams_prefixes = false;
    /// Bytes the arena and the per-brick tables take.
    std::uint64_t total_bytes() const;
};

/// Where a backend keeps one bricked model's streamed bricks; BrickStream drives it between frames.
/// Offsets are bytes from the arena's start (multiples of 64); leaf bounds are addressed as
/// core::BrickLeafBounds indices from the arena's start (BrickView::leaf_bounds = the arena).
class BrickStorage {
public:
    static constexpr std::uint64_t k_not_resident = ~std::uint64_t{0};
    virtual ~BrickStorage() = default;
    /// Whether the storage derives a brick's leaf bounds from its payload itself (the CUDA storage,
    /// on the GPU): upload() then gets no bounds and the host does not compute them.
    virtual bool derives_leaf_bounds() const { return false; }
    /// Copies a validated payload to `offset` and its leaf bounds to `bounds_offset` (empty `bounds`
    /// where derives_leaf_bounds(): derived there at commit()); visible to frames after commit().
    virtual void upload(std::uint64_t offset, std::span<const unsigned char> payload,
                        std::uint64_t bounds_offset, std::span<const core::BrickLeafBounds> bounds) = 0;
    /// Brick b's payload is now at `offset` (k_not_resident: not resident) and its first leaf bound
    /// at index `first_bound`; applied at commit().
    virtual void set_resident(std::uint32_t brick, std::uint64_t offset, std::uint32_t first_bound) = 0;
    /// Streamed prefixes (BrickArena::streams_prefixes): copies the first K = nodes.size() nodes of
    /// a brick's LOD prefix to `offset` (a multiple of 64) as core::BrickView::prefix_first reads
    /// them: K as a word, the K node words, then their K discs (prefix_block_bytes(K) in all);
    /// set_prefix says brick b's prefix is at `offset` (k_not_resident: not resident). Applied at
    /// commit().
    virtual void upload_prefix(std::uint64_t offset, std::span<const std::uint32_t> nodes,
                               std::span<const pool::CompressedSplat> discs) = 0;
    virtual void set_prefix(std::uint32_t brick, std::uint64_t offset) = 0;
    /// core::BrickView::prefix_first of a prefix at `offset` (k_not_resident: core::k_prefix_missing).
    static std::uint32_t prefix_first(std::uint64_t offset);
    /// The bytes upload_prefix writes for K prefix nodes.
    static std::uint64_t prefix_bytes(std::uint32_t nodes);
    /// Makes the uploads and resident changes visible to the next frame (waits for the copies).
    virtual void commit() = 0;
    /// After a frame: sets used[b] / requested[b] / prefix_used[b] (brick_count entries each; the
    /// last all 0 without streamed prefixes) to the frame's flags, and clears them for the next frame.
    virtual void take_flags(std::vector<std::uint32_t>& used, std::vector<std::uint32_t>& requested,
                            std::vector<std::uint32_t>& prefix_used) = 0;
    /// After the backend's set_scene() ran again (BrickStream::set_scene): points the backend's
    /// copy of the model at this storage again. Host storage: nothing to do.
    virtual void reattach() {}
};

/// Host storage (the CPU backend reads the scene's views in place): the arena in
/// host memory; sets model m's brick view in `scene` to its tables.
std::unique_ptr<BrickStorage> make_host_brick_storage(RenderScene& scene, std::size_t model,
                                                      const BrickArena& arena);

/// Streaming settings.
struct StreamOptions {
    /// Bytes the scene may take on the device (CPU: in host memory); 0: unlimited (in core).
    std::uint64_t budget = 0;
    /// Payload bytes uploaded at most per frame (at least one brick is), so frames stay short.
    std::uint64_t upload_per_frame = 256ull << 20;
    /// Uploads stop once the frame (its render, FrameStats::seconds, and the streaming after it)
    /// has taken this long, or a quarter of the render's time after the render where that is later
    /// (at least one brick is uploaded); 0: no time limit.
    double frame_seconds = 0;
    /// Stream the LOD prefixes even where the budget would keep them resident (the default keeps
    /// them resident when they fit and take at most half of a model's arena and prefixes): for a
    /// scene whose views are far, so their rays stop in prefixes and want the room for payloads
    /// nearer.
    bool stream_prefixes = false;
};

/// What streaming did after one frame.
struct StreamFrame {
    bool streaming = false;            ///< false: in core (everything resident)
    std::uint64_t resident_bytes = 0;  ///< always-resident part + resident payloads and their bounds
    std::uint32_t resident_bricks = 0, brick_count = 0;
    std::uint32_t needed = 0;    ///< bricks the frame's rays reached (resident or not)
    std::uint32_t uploaded = 0;  ///< bricks uploaded after the frame
    std::uint64_t uploaded_bytes = 0;
    double upload_seconds = 0;   ///< checksums, leaf bounds and copies
    double prepare_seconds = 0;  ///< of which checksums and leaf bounds (host threads)
    double copy_seconds = 0;     ///< of which copies into the storage (and its commit)
    std::uint32_t evicted = 0;
    /// Streamed LOD prefixes (StreamFrame::streamed_prefixes): resident, uploaded and evicted
    /// after the frame (a brick's prefix is uploaded before its payload, evicted with it). A
    /// prefix first streams its coarse part (its levels above the deepest); a ray that needs more
    /// has it deepened (prefixes_deepened, counted in prefixes_uploaded too: the whole prefix in a
    /// new block), and only a brick whose whole prefix is resident has its payload uploaded.
    bool streamed_prefixes = false;
    std::uint32_t resident_prefixes = 0, prefixes_uploaded = 0, prefixes_deepened = 0, prefixes_evicted = 0;
    std::uint32_t missing = 0;        ///< bricks requested and still not resident after the uploads
    std::uint64_t fallback_rays = 0;  ///< the frame's rays that used a LOD disc (FrameStats::fallbacks)
    /// The frame used no LOD disc: its image equals the in-core render.
    bool converged() const { return fallback_rays == 0; }
    /// Something was uploaded (bricks or LOD prefixes): the next frame may fall back less.
    bool progressed() const { return uploaded > 0 || prefixes_uploaded > 0; }
    /// Requests remain and no room could be freed: the arena holds only bricks the frame used (the
    /// budget holds fewer bricks than the view needs).
    bool stalled = false;
    /// Uploads stopped at StreamOptions::frame_seconds, bricks left for the next frames.
    bool timed_out = false;
    double gb_per_s() const { return upload_seconds > 0 ? uploaded_bytes / upload_seconds * 1e-9 : 0.0; }
};

/// Passes over one still view (prt-play --converge, prt-bench's refinement): more() says whether
/// another pass may still lower the fallbacks. False once a pass has none (converged), uploaded
/// nothing (stalled), or k_patience passes in a row went no lower than the fewest so far: the
/// uploads then only evict blocks the view needs elsewhere (a ray that falls back earlier flags
/// nothing past that point, so such blocks look unused), the budget holding less than the view
/// needs.
class Refinement {
public:
    static constexpr std::uint32_t k_patience = 32;
    bool more(const StreamFrame& f) {
        if (f.converged()) return false;
        if (!f.progressed()) return false;
        if (f.fallback_rays < m_best) {
            m_best = f.fallback_rays;
            m_flat = 0;
            return true;
        }
        return ++m_flat < k_patience;
    }

private:
    std::uint64_t m_best = ~std::uint64_t{0};
    std::uint32_t m_flat = 0;
};

/// The per-frame line: "resident 1.2 MiB (12 of 300 bricks), uploaded 4 bricks (40 KiB, 0.8 GB/s:
/// checks 0.1 ms, copies 0.0 ms), evicted 2, 130 rays fell back".
std::string describe(const StreamFrame& f);

class BrickStream {
public:
    /// Makes `scene` (loaded with LoadOptions::defer_bricks) current on `backend`: in core when the
    /// whole scene fits options.budget (or the budget is 0, or the scene has no deferred bricks:
    /// every brick checked and loaded as RenderScene::load does), else with the always-resident
    /// part and an empty arena (BrickStorage from backend.make_brick_storage, else host storage).
    /// Throws prt::Error when the budget cannot hold the always-resident part and the largest brick
    /// of each bricked model (the line says the minimum), or a brick is corrupted (in core).
    BrickStream(RenderScene& scene, Backend& backend, const StreamOptions& options);
    ~BrickStream();
    BrickStream(const BrickStream&) = delete;
    BrickStream& operator=(const BrickStream&) = delete;

    /// Makes `view` (the scene's view(), e.g. with other materials) current on the backend again,
    /// keeping the resident bricks. Returns the backend's set_scene() statistics.
    UploadStats set_scene(const core::SceneView& view);
    /// The set_scene() statistics.
    const UploadStats& upload_stats() const { return m_upload; }
    bool streaming() const { return !m_models.empty(); }
    /// The bytes the scene takes in core, and the least budget streaming needs.
    std::uint64_t in_core_bytes() const { return m_in_core_bytes; }
    std::uint64_t minimum_bytes() const { return m_minimum_bytes; }
    /// The always-resident bytes (top trees, tables, LOD discs, per-brick tables, other models).
    std::uint64_t fixed_bytes() const { return m_fixed_bytes; }
    /// Arena bytes over all bricked models (payloads and, where they stream, LOD prefixes), and bricks.
    std::uint64_t arena_bytes() const;
    std::uint32_t brick_count() const;
    /// After a frame rendered with `stats`: reads the flags, uploads requested bricks (evicting
    /// least recently used ones the frame did not use) for the next frame. Throws prt::Error
    /// "POOL: section brick_data: brick I: ..." when a brick to upload is corrupted.
    StreamFrame after_frame(const FrameStats& stats);

private:
    struct Model;
    RenderScene& m_scene;
    Backend& m_backend;
    StreamOptions m_options;
    UploadStats m_upload;
    std::uint64_t m_in_core_bytes = 0, m_minimum_bytes = 0, m_fixed_bytes = 0;
    std::uint64_t m_frame = 0;
    std::vector<std::unique_ptr<Model>> m_models;
};

}  // namespace prt::rt
