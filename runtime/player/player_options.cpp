#include "player_options.h"

namespace prt::player {

void add_render_options(CLI::App& app, RenderOverrides& o) {
    app.add_option("--tonemap", o.tone_map,
                   "Tone mapping before gamma for 8-bit output: clamp, reinhard or aces")
        ->check(CLI::IsMember({"clamp", "reinhard", "aces"}));
    app.add_option("--exposure", o.exposure,
                   "Multiply radiance by this before tone mapping (0: the scene's, default 1)")
        ->check(CLI::NonNegativeNumber);
    app.add_option("--max-bounces", o.max_bounces,
                   "Reflection/refraction depth (-1: the scene's, default 4; at most 16)")
        ->check(CLI::Range(-1, 16));
    app.add_flag("--no-shadows", o.no_shadows, "Trace no shadow rays");
    app.add_flag("--no-reflections", o.no_reflections, "Trace no reflected rays");
    app.add_flag("--no-refractions", o.no_refractions, "Trace no refracted rays");
    app.add_flag("--deep-blending", o.deep_blending, "Blend splats across leaf borders (thesis 3.5)");
    app.add_option("--blend-window", o.blend_window,
                   "Blend hits up to this many radii of the nearest splat behind it (thesis 3.3)")
        ->check(CLI::PositiveNumber);
    app.add_option("--max-steps", o.max_steps,
                   "Octree leaves one ray may visit per model (walks cut here are counted)")
        ->check(CLI::Range(1u, 1u << 30));
    app.add_option("--leaf-culling", o.leaf_culling,
                   "Pass octree leaves unread when their bounds rule out a hit: 0 off, 1 normal cones (rays "
                   "leaving a surface skip it), 2 cones and slabs. The image is the same; for comparisons")
        ->check(CLI::Range(0u, 2u));
    app.add_option("--surface", o.surface,
                   "Trace every model as this surface: splats (thesis 3), iso (thesis 4), mls (WS05), patches "
                   "(seed 002) or auto (what each pool holds); default: each model's scene setting, and auto "
                   "for a pool given alone")
        ->check(CLI::IsMember({"splats", "iso", "mls", "patches", "auto"}));
    app.add_flag("--iso-float", o.iso_float,
                 "ISO: trace the float leaves (160 B) instead of the quantized ones (56 B, thesis 4.4) when the "
                 "pool has both");
    app.add_option("--iso-samples", o.iso_samples,
                   "ISO: sample intervals per leaf edge of ray length (thesis 4.5; 0: the default, 4)")
        ->check(CLI::Range(0.0f, 64.0f));
    app.add_option("--iso-refine", o.iso_refine,
                   "ISO: regula falsi steps after the interpolated root (-1: the default, 2; 0: the thesis's "
                   "single interpolation)")
        ->check(CLI::Range(-1, 16));
    app.add_option("--mls-samples", o.mls_samples,
                   "MLS: samples per kd-tree cell interval, k (WS05 3.2; 0: the default, 4)")
        ->check(CLI::Range(0u, 64u));
    app.add_option("--mls-refine", o.mls_refine,
                   "MLS: regula falsi steps after the sign change (-1: the default, 1; 0: WS05's interpolation)")
        ->check(CLI::Range(-1, 16));
    app.add_option("--patch-iterations", o.patch_iterations,
                   "Patches: Newton iteration cap (seed 002, 3; 0: the default, 16)")
        ->check(CLI::Range(0u, 64u));
}

void add_sampling_options(CLI::App& app, RenderOverrides& o) {
    app.add_flag("--path-tracing", o.path_tracing,
                 "Path trace (seed 002, 7: diffuse bounces, perfect mirrors and glass, direct light from every "
                 "light) instead of Whitted ray tracing; default: the scene's render.path_tracing (false)");
    app.add_option("--spp", o.spp,
                   "Samples per pixel per frame, stratified and jittered (0: the scene's render.spp, default 1)")
        ->check(CLI::Range(0u, 65536u));
    app.add_option("--max-depth", o.max_depth,
                   "Path tracing: the depth at which a path gathers direct light and ends (0: the default, 10)")
        ->check(CLI::Range(0u, 64u));
}

rt::LoadOptions load_options(const RenderOverrides& o) {
    rt::LoadOptions l;
    l.surface = o.surface;
    l.iso_float = o.iso_float;
    return l;
}

void add_backend_options(CLI::App& app, BackendChoice& b) {
    app.add_option("--backend", b.name,
                   "cpu, cuda, hybrid (GPU and CPU share each frame) or auto (cuda if a GPU exists)")
        ->check(CLI::IsMember({"cpu", "cuda", "hybrid", "auto"}));
    app.add_option("--kernel", b.kernel,
                   "CUDA kernel structure: mega (one kernel) or wavefront (several, thesis 2.4)")
        ->check(CLI::IsMember({"mega", "wavefront"}));
    app.add_option("--mapping", b.mapping, "CUDA ray-to-thread mapping: zorder (thesis 2.3) or linear")
        ->check(CLI::IsMember({"zorder", "linear"}));
    app.add_option("--threads", b.threads, "CPU backend threads (0: all hardware threads)");
    app.add_option(
           "--min-blocks", b.min_blocks,
           "CUDA megakernel occupancy hint: resident 256-thread blocks per SM, 1-6, which caps registers "
           "per thread (0: the measured default, 4; 2 for patch-only scenes, whose kernel has variants 1, 2 "
           "and 4)")
        ->check(CLI::Range(0, 6));
    app.add_flag("--default-carveout", b.default_carveout,
                 "CUDA: leave the L1 / shared-memory split to the driver instead of preferring L1");
}

void apply(const RenderOverrides& o, core::RenderParams& p) {
    p.tone_map = o.tone_map == "reinhard" ? core::ToneMap::reinhard
                 : o.tone_map == "aces"   ? core::ToneMap::aces
                                          : core::ToneMap::clamp;
    if (o.exposure > 0) p.exposure = o.exposure;
    if (o.max_bounces >= 0) p.max_bounces = static_cast<std::uint32_t>(o.max_bounces);
    if (o.no_shadows) p.shadows = 0;
    if (o.no_reflections) p.reflections = 0;
    if (o.no_refractions) p.refractions = 0;
    if (o.path_tracing) p.path_tracing = 1;
    if (o.spp > 0) p.spp = o.spp;
    if (o.max_depth > 0) p.max_path_depth = o.max_depth;
    if (o.iso_samples > 0) p.iso.samples = o.iso_samples;
    if (o.iso_refine >= 0) p.iso.refine_steps = static_cast<std::uint32_t>(o.iso_refine);
    if (o.mls_samples >= 2) p.mls.samples = o.mls_samples;
    if (o.mls_refine >= 0) p.mls.refine_steps = static_cast<std::uint32_t>(o.mls_refine);
    if (o.patch_iterations > 0) p.patch.max_iterations = o.patch_iterations;
    p.deep_blending = o.deep_blending ? 1u : 0u;
    p.blend_window = o.blend_window;
    p.max_steps = o.max_steps;
    p.leaf_culling = o.leaf_culling;
}

rt::BackendOptions backend_options(const BackendChoice& b) {
    rt::BackendOptions o;
    o.cpu_threads = b.threads;
    o.cuda_wavefront = b.kernel == "wavefront";
    o.cuda_linear_mapping = b.mapping == "linear";
    o.cuda_min_blocks = b.min_blocks;
    o.cuda_max_l1 = !b.default_carveout;
    return o;
}

}  // namespace prt::player
