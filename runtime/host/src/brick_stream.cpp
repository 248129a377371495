// PointRT runtime (host): streaming bricks under a memory budget (prt/runtime/brick_stream.h).
#include "prt/runtime/brick_stream.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <map>
#include <new>
#include <optional>

#include "prt/error.h"
#include "prt/formats/brick_sections.h"
#include "prt/parallel.h"
#include "prt/runtime/leaf_bounds.h"
#include "prt/tool_util.h"

namespace prt::rt {

namespace {

/// The largest arena of one model: its leaf bounds are found by 32-bit indices from its start.
constexpr std::uint64_t k_max_arena_bytes = (std::uint64_t{1} << 32) * sizeof(core::BrickLeafBounds);
/// Per-brick tables always resident: the resident table (a pointer), the first leaf bound, the
/// use and request flags.
constexpr std::uint64_t k_table_bytes_per_brick = sizeof(void*) + 3 * sizeof(std::uint32_t);
/// A LOD prefix node: its word (lod_nodes) and its disc (lod_discs).
constexpr std::uint64_t k_prefix_node_bytes = sizeof(std::uint32_t) + sizeof(pool::CompressedSplat);
/// Per-brick tables of streamed prefixes: where each starts, its use flag.
constexpr std::uint64_t k_prefix_table_bytes_per_brick = 2 * sizeof(std::uint32_t);
/// The largest arena of a model whose prefixes stream: BrickView::prefix_first indexes its words
/// with 32 bits.
constexpr std::uint64_t k_max_prefix_arena_bytes = (std::uint64_t{1} << 32) * sizeof(std::uint32_t) - 64;

/// BrickView::prefix_first of a prefix block at `offset` of the arena (k_not_resident: missing):
/// its node words, after its node count.
std::uint32_t prefix_first_word(std::uint64_t offset) {
    return offset == BrickStorage::k_not_resident
               ? core::k_prefix_missing
               : static_cast<std::uint32_t>(offset / sizeof(std::uint32_t) + 1);
}

std::uint64_t round_up_64(std::uint64_t n) {
    return (n + 63) / 64 * 64;
}

/// The block of a streamed prefix of `nodes` nodes: its node count, node words and discs.
std::uint64_t prefix_block_bytes(std::uint32_t nodes) {
    return round_up_64(sizeof(std::uint32_t) + std::uint64_t{nodes} * k_prefix_node_bytes);
}

/// The coarse part of a brick's LOD prefix (its node words, breadth first): the nodes above its
/// deepest level, or all of them when it has one level. A breadth-first prefix of the brick again,
/// so the walk needs nothing else to use it: an inner node of its last level addresses children
/// past its end, where a ray that must go deeper falls back and asks for the whole prefix.
std::uint32_t coarse_prefix_nodes(std::span<const std::uint32_t> nodes) {
    const auto count = static_cast<std::uint32_t>(nodes.size());
    std::uint32_t begin = 0, end = std::min<std::uint32_t>(count, 1);  // the level [begin, end)
    while (end < count) {
        std::uint64_t next = end;
        for (std::uint32_t i = begin; i < end; ++i)
            if (core::node_is_internal(nodes[i])) next += 8;
        if (next <= end) break;  // no inner node: nothing deeper (a corrupt count)
        begin = end;
        end = static_cast<std::uint32_t>(std::min<std::uint64_t>(next, count));
    }
    return begin > 0 ? begin : count;
}

/// Host storage: one 64-byte aligned arena in host memory.
class HostBrickStorage final : public BrickStorage {
public:
    HostBrickStorage(RenderScene& scene, std::size_t model, const BrickArena& a) {
        m_arena.reset(static_cast<unsigned char*>(::operator new (
            static_cast<std::size_t>(std::max<std::uint64_t>(a.bytes, 64)), std::align_val_t{64})));
        m_resident.assign(a.brick_count, nullptr);
        m_first.assign(std::size_t{a.brick_count} + 1, 0);
        m_used.assign(a.brick_count, 0);
        m_requested.assign(a.brick_count, 0);
        core::BrickView v = scene.models().at(model).view.bricks;
        v.resident = m_resident.data();
        v.leaf_bounds = reinterpret_cast<const core::BrickLeafBounds*>(m_arena.get());
        v.leaf_bounds_first = m_first.data();
        v.used = m_used.data();
        v.requests = m_requested.data();
        if (a.streams_prefixes) {
            m_prefix_first.assign(a.brick_count, core::k_prefix_missing);
            m_prefix_used.assign(a.brick_count, 0);
            v.lod_nodes = reinterpret_cast<const std::uint32_t*>(m_arena.get());
            v.lod_discs = nullptr;
            v.lod_node_count = 0;
            v.prefix_first = m_prefix_first.data();
            v.prefix_used = m_prefix_used.data();
        }
        scene.set_brick_view(model, v);
    }

    void upload(std::uint64_t offset, std::span<const unsigned char> payload, std::uint64_t bounds_offset,
                std::span<const core::BrickLeafBounds> bounds) override {
        std::memcpy(m_arena.get() + offset, payload.data(), payload.size());
        std::memcpy(m_arena.get() + bounds_offset, bounds.data(), bounds.size_bytes());
    }
    void set_resident(std::uint32_t brick, std::uint64_t offset, std::uint32_t first_bound) override {
        m_resident[brick] = offset == k_not_resident ? nullptr : m_arena.get() + offset;
        m_first[brick] = offset == k_not_resident ? 0 : first_bound;
    }
    void upload_prefix(std::uint64_t offset, std::span<const std::uint32_t> nodes,
                       std::span<const pool::CompressedSplat> discs) override {
        const auto count = static_cast<std::uint32_t>(nodes.size());
        unsigned char* at = m_arena.get() + offset;
        std::memcpy(at, &count, sizeof(count));
        std::memcpy(at + sizeof(count), nodes.data(), nodes.size_bytes());
        std::memcpy(at + sizeof(count) + nodes.size_bytes(), discs.data(), discs.size_bytes());
    }
    void set_prefix(std::uint32_t brick, std::uint64_t offset) override {
        m_prefix_first[brick] = prefix_first_word(offset);
    }
    void commit() override {}
    void take_flags(std::vector<std::uint32_t>& used, std::vector<std::uint32_t>& requested,
                    std::vector<std::uint32_t>& prefix_used) override {
        used = m_used;
        requested = m_requested;
        prefix_used = m_prefix_used;
        prefix_used.resize(m_used.size(), 0u);
        std::fill(m_used.begin(), m_used.end(), 0u);
        std::fill(m_requested.begin(), m_requested.end(), 0u);
        std::fill(m_prefix_used.begin(), m_prefix_used.end(), 0u);
    }

private:
    struct AlignedDelete {
        void operator()(unsigned char* p) const { ::operator delete (p, std::align_val_t{64}); }
    };
    std::unique_ptr<unsigned char, AlignedDelete> m_arena;
    std::vector<const unsigned char*> m_resident;
    std::vector<std::uint32_t> m_first, m_used, m_requested;
    std::vector<std::uint32_t> m_prefix_first, m_prefix_used;
};

/// First-fit allocation of 64-byte multiples in [0, size), free blocks merged with their neighbours.
class ArenaAllocator {
public:
    explicit ArenaAllocator(std::uint64_t size) : m_free_bytes(size) {
        if (size > 0) m_free.emplace(0, size);
    }
    /// Free bytes in all (in blocks of any size).
    std::uint64_t free_bytes() const { return m_free_bytes; }
    /// The offset of a free block of `bytes`, or nullopt.
    std::optional<std::uint64_t> allocate(std::uint64_t bytes) {
        for (auto it = m_free.begin(); it != m_free.end(); ++it) {
            if (it->second < bytes) continue;
            const std::uint64_t at = it->first, left = it->second - bytes;
            m_free.erase(it);
            m_free_bytes -= bytes;
            if (left > 0) m_free.emplace(at + bytes, left);
            return at;
        }
        return std::nullopt;
    }
    void release(std::uint64_t at, std::uint64_t bytes) {
        m_free_bytes += bytes;
        auto next = m_free.lower_bound(at);
        if (next != m_free.end() && next->first == at + bytes) {
            bytes += next->second;
            next = m_free.erase(next);
        }
        if (next != m_free.begin()) {
            auto prev = std::prev(next);
            if (prev->first + prev->second == at) {
                prev->second += bytes;
                return;
            }
        }
        m_free.emplace(at, bytes);
    }

private:
    std::map<std::uint64_t, std::uint64_t> m_free;  ///< offset -> bytes
    std::uint64_t m_free_bytes = 0;
};

/// The block a brick takes: its payload, then its leaf bounds, each rounded up to 64 bytes.
std::uint64_t block_bytes(const pool::BrickEntry& e) {
    return round_up_64(e.size) + round_up_64(std::uint64_t{e.leaf_count} * sizeof(core::BrickLeafBounds));
}

}  // namespace

std::uint64_t BrickArena::total_bytes() const {
    return bytes + std::uint64_t{brick_count} * k_table_bytes_per_brick +
           (streams_prefixes ? std::uint64_t{brick_count} * k_prefix_table_bytes_per_brick : 0);
}

std::uint32_t BrickStorage::prefix_first(std::uint64_t offset) {
    return prefix_first_word(offset);
}

std::uint64_t BrickStorage::prefix_bytes(std::uint32_t nodes) {
    return sizeof(std::uint32_t) + std::uint64_t{nodes} * k_prefix_node_bytes;
}

std::unique_ptr<BrickStorage> make_host_brick_storage(RenderScene& scene, std::size_t model,
                                                      const BrickArena& arena) {
    return std::make_unique<HostBrickStorage>(scene, model, arena);
}

std::string describe(const StreamFrame& f) {
    char buf[512];
    std::snprintf(buf, sizeof(buf),
                  "resident %s (%u of %u bricks), uploaded %u bricks (%s, %.2f GB/s: checks %.1f ms, copies "
                  "%.1f ms), evicted %u, %llu rays fell back",
                  tool::format_bytes(f.resident_bytes).c_str(), f.resident_bricks, f.brick_count, f.uploaded,
                  tool::format_bytes(f.uploaded_bytes).c_str(), f.gb_per_s(), f.prepare_seconds * 1e3,
                  f.copy_seconds * 1e3, f.evicted, static_cast<unsigned long long>(f.fallback_rays));
    std::string out = buf;
    if (f.streamed_prefixes)
        out += "; LOD prefixes: " + std::to_string(f.resident_prefixes) + " resident, " +
               std::to_string(f.prefixes_uploaded) + " uploaded (" + std::to_string(f.prefixes_deepened) +
               " deepened), " + std::to_string(f.prefixes_evicted) + " evicted";
    if (f.timed_out)
        out += "; " + std::to_string(f.missing) + " requested bricks wait for the next frames (--frame-time)";
    return out;
}

struct BrickStream::Model {
    std::size_t index = 0;
    const pool::PoolFile* pool = nullptr;
    pool::BrickSections sections;
    BrickArena arena;
    std::uint64_t data_bytes = 0;
    std::uint64_t largest_block = 0;
    std::vector<const unsigned char*> placeholder;  ///< resident table before the storage exists
    std::vector<std::uint32_t> placeholder_prefix;  ///< and prefix table, with streamed prefixes
    std::unique_ptr<BrickStorage> storage;
    std::unique_ptr<ArenaAllocator> allocator;
    std::vector<std::uint64_t> block_of;   ///< per brick: its block's offset or k_not_resident
    std::vector<std::uint64_t> last_used;  ///< per brick: the last frame that used it (0: none)
    std::vector<std::uint32_t> used, requested;
    std::uint32_t resident = 0;
    std::uint64_t resident_bytes = 0;  ///< the resident bricks' blocks
    // LOD prefixes: their nodes in all, the largest one's; streamed (arena.streams_prefixes) in
    // blocks of the arena: each brick's prefix block (k_not_resident: none), how many of its nodes
    // it holds (its coarse part or all), the coarse part's size, and the last frame that used it.
    std::uint64_t prefix_total = 0;
    std::uint32_t largest_prefix = 0;
    std::vector<std::uint64_t> prefix_of;
    std::vector<std::uint32_t> prefix_nodes, coarse_nodes;
    std::vector<std::uint64_t> prefix_last_used;
    std::vector<std::uint32_t> prefix_used;
    std::uint32_t resident_prefixes = 0;
    std::uint64_t resident_prefix_bytes = 0;

    bool streams_prefixes() const { return arena.streams_prefixes; }
    std::uint32_t prefix_size(std::uint32_t b) const { return sections.lod_table[b].node_count; }
    /// Brick b's resident prefix block.
    std::uint64_t prefix_block(std::uint32_t b) const { return prefix_block_bytes(prefix_nodes[b]); }
    void evict(std::uint32_t b) {
        const std::uint64_t bytes = block_bytes(sections.table[b]);
        allocator->release(block_of[b], bytes);
        storage->set_resident(b, BrickStorage::k_not_resident, 0);
        block_of[b] = BrickStorage::k_not_resident;
        resident_bytes -= bytes;
        --resident;
    }
    /// Evicts brick b's streamed prefix, and its payload with it (a resident payload needs its
    /// prefix's discs); true when the payload was resident.
    bool evict_prefix(std::uint32_t b) {
        const bool payload = block_of[b] != BrickStorage::k_not_resident;
        if (payload) evict(b);
        allocator->release(prefix_of[b], prefix_block(b));
        storage->set_prefix(b, BrickStorage::k_not_resident);
        prefix_of[b] = BrickStorage::k_not_resident;
        resident_prefix_bytes -= prefix_block(b);
        prefix_nodes[b] = 0;
        --resident_prefixes;
        return payload;
    }
};

BrickStream::~BrickStream() = default;

BrickStream::BrickStream(RenderScene& scene, Backend& backend, const StreamOptions& options)
    : m_scene(scene), m_backend(backend), m_options(options) {
    m_fixed_bytes = scene.bytes();
    m_in_core_bytes = scene.bytes();
    std::vector<std::unique_ptr<Model>> models;
    std::uint64_t block_minimum = 0;
    for (std::size_t i = 0; i < scene.models().size(); ++i) {
        const LoadedModel& lm = scene.models()[i];
        if (!lm.bricks_deferred) continue;
        auto m = std::make_unique<Model>();
        m->index = i;
        m->pool = lm.pool.get();
        m->sections = pool::validate_brick_index(*lm.pool);  // as at the load: the index only
        const std::uint32_t bricks = m->sections.info.brick_count;
        m->arena.brick_count = bricks;
        std::uint64_t leaves = 0;
        for (const pool::BrickEntry& e : m->sections.table) {
            m->largest_block = std::max(m->largest_block, block_bytes(e));
            leaves += e.leaf_count;
        }
        m->data_bytes = m->sections.data.size();
        m_in_core_bytes +=
            m->data_bytes + leaves * sizeof(core::BrickLeafBounds) + (std::uint64_t{bricks} + 1) * 4;
        m_fixed_bytes += std::uint64_t{bricks} * k_table_bytes_per_brick;
        block_minimum += m->largest_block;
        if (!m->sections.lod_table.empty()) {
            // Prefixes may stream: the least budget counts the largest one and the prefix tables,
            // not every prefix (the scene's bytes count them all: taken back out here).
            m->prefix_total = m->sections.lod_nodes.size();
            for (const pool::BrickLod& l : m->sections.lod_table)
                m->largest_prefix = std::max(m->largest_prefix, l.node_count);
            m_fixed_bytes -= m->prefix_total * k_prefix_node_bytes;
            block_minimum += prefix_block_bytes(m->largest_prefix) +
                             std::uint64_t{bricks} * k_prefix_table_bytes_per_brick;
        }
        models.push_back(std::move(m));
    }
    m_minimum_bytes = m_fixed_bytes + block_minimum;
    const bool in_core =
        models.empty() || options.budget == 0 || m_in_core_bytes <= options.budget || !backend.can_stream();
    if (in_core) {
        scene.load_deferred_bricks();
        m_upload = backend.set_scene(scene.view());
        return;
    }
    if (options.budget < m_minimum_bytes)
        throw Error("memory budget " + tool::format_bytes(options.budget) +
                    " is too small: the bricked scene needs at least " + tool::format_bytes(m_minimum_bytes) +
                    " (top tree, brick table, LOD discs, per-brick tables and other models " +
                    tool::format_bytes(m_fixed_bytes) +
                    ", plus the largest brick and LOD prefix of each bricked model; " +
                    tool::format_bytes(m_in_core_bytes) + " holds it all in core)");
    // The LOD prefixes stay resident (with the top tree) when the budget holds them and, for each
    // model, they would take at most half of what its arena and prefixes get (a quarter until
    // 2026-12-04: the 500M room under an eighth of its pool then streamed its 313 MiB of prefixes,
    // and its orbit took 17 passes a frame against 6); else every
    // model's prefixes stream too, into the same arena as its payloads (a block each), so a far
    // view's bricks need their prefixes only and the view's demand shares the arena between
    // prefixes and payloads.
    std::uint64_t prefix_bytes = 0, tables = 0, largest_blocks = 0, data_total = 0;
    for (const auto& m : models) {
        prefix_bytes += m->prefix_total * k_prefix_node_bytes;
        if (m->prefix_total > 0)
            tables += std::uint64_t{m->arena.brick_count} * k_prefix_table_bytes_per_brick;
        largest_blocks += m->largest_block;
        data_total += m->data_bytes;
    }
    const auto share = [&](const Model& m, std::uint64_t spare) {  // of the spare budget, 64-byte steps
        const double part = data_total > 0 ? static_cast<double>(m.data_bytes) / data_total : 1.0;
        return static_cast<std::uint64_t>(part * static_cast<double>(spare)) / 64 * 64;
    };
    const std::uint64_t resident_fixed = m_fixed_bytes + prefix_bytes;
    bool stream_prefixes =
        prefix_bytes > 0 && (options.stream_prefixes || options.budget < resident_fixed + largest_blocks);
    for (const auto& m : models)
        if (!stream_prefixes && m->prefix_total > 0) {
            const std::uint64_t mine = m->prefix_total * k_prefix_node_bytes;
            const std::uint64_t arena =
                m->largest_block + share(*m, options.budget - resident_fixed - largest_blocks);
            stream_prefixes = mine > arena;  // more than half
        }
    m_fixed_bytes += stream_prefixes ? tables : prefix_bytes;
    // The arenas: the budget left after the always-resident part, shared in proportion to the
    // models' brick data, each at least its largest brick (and, streamed, its largest prefix).
    const std::uint64_t spare = options.budget - m_fixed_bytes - largest_blocks;
    for (auto& m : models) {
        std::uint64_t bytes = m->largest_block + share(*m, spare);
        std::uint64_t max_arena = k_max_arena_bytes;
        if (stream_prefixes && m->prefix_total > 0) {
            m->arena.streams_prefixes = true;
            max_arena = k_max_prefix_arena_bytes;
            m->prefix_of.assign(m->arena.brick_count, BrickStorage::k_not_resident);
            m->prefix_nodes.assign(m->arena.brick_count, 0);
            m->coarse_nodes.resize(m->arena.brick_count);
            for (std::uint32_t b = 0; b < m->arena.brick_count; ++b) {
                const pool::BrickLod& l = m->sections.lod_table[b];
                m->coarse_nodes[b] = coarse_prefix_nodes(
                    m->sections.lod_nodes.subspan(static_cast<std::size_t>(l.first), l.node_count));
            }
            m->prefix_last_used.assign(m->arena.brick_count, 0);
        }
        // At most 64 GiB a model (k_max_arena_bytes; 16 GiB with streamed prefixes): the rest of a
        // larger budget stays unused.
        m->arena.bytes = std::min<std::uint64_t>(bytes, max_arena);
        m->allocator = std::make_unique<ArenaAllocator>(m->arena.bytes);
        m->block_of.assign(m->arena.brick_count, BrickStorage::k_not_resident);
        m->last_used.assign(m->arena.brick_count, 0);
        // Until the storage exists: no brick resident, no leaf bounds (so a backend uploading the
        // scene knows these bricks are streamed, and leaves brick_data where it is).
        m->placeholder.assign(m->arena.brick_count, nullptr);
        core::BrickView v = scene.models()[m->index].view.bricks;
        v.resident = m->placeholder.data();
        v.leaf_bounds = nullptr;
        v.leaf_bounds_first = nullptr;
        if (m->streams_prefixes()) {  // no prefix in the scene: the storage's arenas hold them
            m->placeholder_prefix.assign(m->arena.brick_count, core::k_prefix_missing);
            v.lod_nodes = nullptr;
            v.lod_discs = nullptr;
            v.lod_node_count = 0;
            v.prefix_first = m->placeholder_prefix.data();
        }
        scene.set_brick_view(m->index, v);
    }
    m_upload = backend.set_scene(scene.view());
    for (auto& m : models) {
        const auto idx = static_cast<std::uint32_t>(m->index);
        m->storage = backend.make_brick_storage(idx, scene.models()[m->index].view.bricks, m->arena);
        if (!m->storage) m->storage = make_host_brick_storage(scene, m->index, m->arena);
    }
    m_models = std::move(models);
}

UploadStats BrickStream::set_scene(const core::SceneView& view) {
    const UploadStats up = m_backend.set_scene(view);
    for (auto& m : m_models) m->storage->reattach();
    return up;
}

std::uint64_t BrickStream::arena_bytes() const {
    std::uint64_t n = 0;
    for (const auto& m : m_models) n += m->arena.bytes;
    return n;
}

std::uint32_t BrickStream::brick_count() const {
    std::uint32_t n = 0;
    for (const auto& m : m_models) n += m->arena.brick_count;
    return n;
}

StreamFrame BrickStream::after_frame(const FrameStats& stats) {
    StreamFrame f;
    f.fallback_rays = stats.fallbacks;
    if (m_models.empty()) {
        f.resident_bytes = m_scene.bytes();
        for (const LoadedModel& lm : m_scene.models()) f.brick_count += lm.view.bricks.brick_count;
        f.resident_bricks = f.brick_count;
        return f;
    }
    f.streaming = true;
    ++m_frame;
    const auto start = std::chrono::steady_clock::now();
    std::uint64_t allowance = m_options.upload_per_frame;
    struct Upload {
        Model* model;
        std::uint32_t brick;
        std::uint64_t offset;
        std::vector<core::BrickLeafBounds> bounds;
    };
    std::vector<Upload> uploads;
    for (auto& mp : m_models) {
        Model& m = *mp;
        m.storage->take_flags(m.used, m.requested, m.prefix_used);
        const bool prefixes = m.streams_prefixes();
        // Wanted: streamed prefixes first (with one, a brick's rays may stop in it and need no
        // payload): missing ones' coarse parts (so a view whose demand exceeds the arena fits
        // more of it: only bricks whose rays go deeper take their whole prefix, a pass later),
        // then whole prefixes where rays went below a coarse part; then payloads (a brick whose
        // whole prefix is resident).
        struct Want {
            std::uint32_t brick;
            std::uint32_t prefix_nodes;  // the prefix nodes to upload; 0: the payload
        };
        std::vector<Want> wanted, deeper, payloads;
        for (std::uint32_t b = 0; b < m.arena.brick_count; ++b) {
            if (m.used[b] != 0) {
                m.last_used[b] = m_frame;
                ++f.needed;
            }
            if (prefixes && (m.prefix_used[b] != 0 || m.used[b] != 0)) m.prefix_last_used[b] = m_frame;
            if (m.requested[b] == 0) continue;
            if (prefixes && m.prefix_of[b] == BrickStorage::k_not_resident) {
                wanted.push_back(Want{b, m.coarse_nodes[b]});
            } else if (prefixes && m.prefix_nodes[b] < m.prefix_size(b)) {
                deeper.push_back(Want{b, m.prefix_size(b)});
            } else if (m.block_of[b] == BrickStorage::k_not_resident) {
                payloads.push_back(Want{b, 0});
                ++f.needed;
            }
        }
        wanted.insert(wanted.end(), deeper.begin(), deeper.end());
        wanted.insert(wanted.end(), payloads.begin(), payloads.end());
        if (prefixes) f.streamed_prefixes = true;
        // Eviction candidates: the blocks this frame did not use, least recently used first, a
        // payload before its brick's prefix (evicting a prefix evicts its payload with it).
        struct Victim {
            std::uint64_t last_used;
            std::uint32_t brick;
            bool prefix;
        };
        std::vector<Victim> victims;
        std::uint64_t victim_bytes = 0;  // what evicting every candidate left would free
        for (std::uint32_t b = 0; b < m.arena.brick_count; ++b) {
            if (m.block_of[b] != BrickStorage::k_not_resident && m.last_used[b] < m_frame) {
                victims.push_back(Victim{m.last_used[b], b, false});
                victim_bytes += block_bytes(m.sections.table[b]);
            }
            if (prefixes && m.prefix_of[b] != BrickStorage::k_not_resident &&
                m.prefix_last_used[b] < m_frame) {
                victims.push_back(Victim{m.prefix_last_used[b], b, true});
                victim_bytes += m.prefix_block(b);
            }
        }
        std::sort(victims.begin(), victims.end(), [](const Victim& a, const Victim& b) {
            if (a.last_used != b.last_used) return a.last_used < b.last_used;
            if (a.brick != b.brick) return a.brick < b.brick;
            return !a.prefix && b.prefix;
        });
        std::size_t next_victim = 0, taken = 0;
        const auto evict_next = [&](std::uint32_t keep) {  // the next candidate still resident
            const Victim v = victims[next_victim++];
            if (v.prefix && v.brick == keep) return;  // the prefix being deepened (used: never a candidate)
            if (!v.prefix) {
                if (m.block_of[v.brick] == BrickStorage::k_not_resident) return;  // gone with its prefix
                victim_bytes -= block_bytes(m.sections.table[v.brick]);
                m.evict(v.brick);
                ++f.evicted;
                return;
            }
            victim_bytes -= m.prefix_block(v.brick);
            if (m.block_of[v.brick] != BrickStorage::k_not_resident)  // unused too: counted as a candidate
                victim_bytes -= block_bytes(m.sections.table[v.brick]);
            if (m.evict_prefix(v.brick)) ++f.evicted;
            ++f.prefixes_evicted;
        };
        for (const Want& w : wanted) {
            const std::uint32_t b = w.brick;
            const bool prefix = w.prefix_nodes > 0;
            const std::uint64_t size =
                prefix ? BrickStorage::prefix_bytes(w.prefix_nodes) : m.sections.table[b].size;
            if ((!uploads.empty() || f.prefixes_uploaded > 0) && size > allowance) break;  // the rest wait
            const std::uint64_t bytes =
                prefix ? prefix_block_bytes(w.prefix_nodes) : block_bytes(m.sections.table[b]);
            std::optional<std::uint64_t> at = m.allocator->allocate(bytes);
            // A prefix deepened gives its coarse block back if nothing else makes room (a budget
            // near the least one holds the largest prefix, not it and its coarse part).
            const std::uint64_t own =
                prefix && m.prefix_of[b] != BrickStorage::k_not_resident ? m.prefix_block(b) : 0;
            // Evict only when it can make room (fragmentation aside): never for nothing.
            if (!at && m.allocator->free_bytes() + victim_bytes + own < bytes) {
                f.stalled = true;
                break;
            }
            while (!at && next_victim < victims.size()) {
                evict_next(b);
                at = m.allocator->allocate(bytes);
            }
            if (!at && own > 0) {
                m.evict_prefix(b);
                ++f.prefixes_evicted;
                at = m.allocator->allocate(bytes);
            }
            if (!at) {
                f.stalled = true;  // the arena holds only blocks this frame used
                break;
            }
            allowance -= std::min(allowance, size);
            ++taken;
            if (prefix) {  // copied at once: its nodes and discs were checked with the pool's index
                const auto first = static_cast<std::size_t>(m.sections.lod_table[b].first);
                m.storage->upload_prefix(*at, m.sections.lod_nodes.subspan(first, w.prefix_nodes),
                                         m.sections.lod_discs.subspan(first, w.prefix_nodes));
                m.storage->set_prefix(b, *at);
                if (m.prefix_of[b] != BrickStorage::k_not_resident) {  // deepened: the coarse block goes
                    m.allocator->release(m.prefix_of[b], m.prefix_block(b));
                    m.resident_prefix_bytes -= m.prefix_block(b);
                    ++f.prefixes_deepened;
                } else {
                    ++m.resident_prefixes;
                }
                m.prefix_of[b] = *at;
                m.prefix_nodes[b] = w.prefix_nodes;
                m.prefix_last_used[b] = m_frame;
                m.resident_prefix_bytes += bytes;
                ++f.prefixes_uploaded;
                f.uploaded_bytes += size;
                continue;
            }
            m.block_of[b] = *at;  // taken now, so a later request of this frame cannot evict it
            m.last_used[b] = m_frame;
            uploads.push_back(Upload{&m, b, *at, {}});
        }
        f.missing += static_cast<std::uint32_t>(wanted.size() - taken);
    }
    // Each brick checked by its own checksum and its leaf bounds computed from it alone (in
    // parallel; on the device by the CUDA storage), then copied into its block. In rounds of 1, 2,
    // 4, ... 512 bricks while the frame (its render, then this) can end within frame_seconds, each
    // round no larger than the time left at the rate of the rounds before, 3 ms kept for the
    // commit (with 1 ms, one pass of the 500M room's orbit took 50.68 ms). The rest give their
    // blocks back and wait for the next frames, so a view that turns to a new region refines over
    // several short frames instead of one long one (the first round, at least, uploads). A render
    // that leaves less than a quarter of its own time (the CPU backend, a large image) gets that
    // quarter: its frames are long anyway, and the view still refines in a few of them.
    const bool timed = m_options.frame_seconds > 0;
    const double stop_after = std::max(m_options.frame_seconds - stats.seconds, 0.25 * stats.seconds) - 3e-3;
    double prepare = 0, copy = 0;
    std::size_t done = 0;
    for (std::size_t round = 1; done < uploads.size(); round = std::min<std::size_t>(2 * round, 512)) {
        if (timed && done > 0) {
            const double spent =
                std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
            const double per_brick = (prepare + copy) / double(done);
            const double fits = (stop_after - spent) / std::max(per_brick, 1e-9);
            if (fits < 1) break;
            round = std::min(round, static_cast<std::size_t>(fits));
        }
        const std::size_t first = done, last = std::min(uploads.size(), done + round);
        const auto prepare_start = std::chrono::steady_clock::now();
        parallel_chunks(last - first, 1, resolve_threads(0), [&](std::size_t i0, std::size_t i1, unsigned) {
            for (std::size_t i = first + i0; i < first + i1; ++i) {
                Upload& u = uploads[i];
                const Model& m = *u.model;
                const pool::BrickEntry& e = m.sections.table[u.brick];
                pool::validate_brick(*m.pool, m.sections, u.brick, m.sections.payload(u.brick));
                if (!m.storage->derives_leaf_bounds())
                    u.bounds = build_one_brick_leaf_bounds(
                        e, reinterpret_cast<const unsigned char*>(m.sections.payload(u.brick).data()));
            }
        });
        const auto copy_start = std::chrono::steady_clock::now();
        for (std::size_t i = first; i < last; ++i) {
            Upload& u = uploads[i];
            Model& m = *u.model;
            const pool::BrickEntry& e = m.sections.table[u.brick];
            const auto payload = m.sections.payload(u.brick);
            const std::uint64_t bounds_offset = u.offset + round_up_64(e.size);
            m.storage->upload(u.offset,
                              {reinterpret_cast<const unsigned char*>(payload.data()), payload.size()},
                              bounds_offset, u.bounds);
            m.storage->set_resident(
                u.brick, u.offset, static_cast<std::uint32_t>(bounds_offset / sizeof(core::BrickLeafBounds)));
            m.resident_bytes += block_bytes(e);
            ++m.resident;
            ++f.uploaded;
            f.uploaded_bytes += e.size;
            std::vector<core::BrickLeafBounds>().swap(u.bounds);
        }
        const auto round_end = std::chrono::steady_clock::now();
        prepare += std::chrono::duration<double>(copy_start - prepare_start).count();
        copy += std::chrono::duration<double>(round_end - copy_start).count();
        done = last;
    }
    for (std::size_t i = done; i < uploads.size(); ++i) {  // out of time: their blocks go back
        Model& m = *uploads[i].model;
        m.allocator->release(uploads[i].offset, block_bytes(m.sections.table[uploads[i].brick]));
        m.block_of[uploads[i].brick] = BrickStorage::k_not_resident;
        ++f.missing;
        f.timed_out = true;
    }
    const auto commit_start = std::chrono::steady_clock::now();
    for (auto& m : m_models) m->storage->commit();
    if (!uploads.empty() || f.prefixes_uploaded > 0) {
        const auto end = std::chrono::steady_clock::now();
        f.upload_seconds = std::chrono::duration<double>(end - start).count();
        f.prepare_seconds = prepare;
        f.copy_seconds = copy + std::chrono::duration<double>(end - commit_start).count();
    }
    f.resident_bytes = m_fixed_bytes;
    for (const auto& m : m_models) {
        f.resident_bytes += m->resident_bytes;
        f.resident_bricks += m->resident;
        f.brick_count += m->arena.brick_count;
        if (!m->streams_prefixes()) continue;
        f.resident_prefixes += m->resident_prefixes;
        f.resident_bytes += m->resident_prefix_bytes;
    }
    return f;
}

}  // namespace prt::rt
