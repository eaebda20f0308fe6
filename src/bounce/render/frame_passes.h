// The passes of a frame as the plan runs them. Every pass receives the one FrameContext
// (scene, BVHs, materials, lights, stats, progress, cancel) and returns a typed result;
// run_frame (render.h) calls them in the plan's order and nothing else does.
#pragma once

#include <memory>
#include <optional>
#include <vector>

#include "bounce/accel/accel.h"
#include "bounce/cache/irradiance_cache.h"
#include "bounce/cache/temporal.h"
#include "bounce/core/communicator.h"
#include "bounce/core/image.h"
#include "bounce/core/progress.h"
#include "bounce/core/stats.h"
#include "bounce/deep/deep_buffer.h"
#include "bounce/gather/gather.h"
#include "bounce/lighting/lighting.h"
#include "bounce/lighting/materials.h"
#include "bounce/radiosity/radiosity.h"
#include "bounce/render/frame_plan.h"
#include "bounce/shade/shade.h"

namespace bounce {

/// What every pass of a frame receives.
struct FrameContext {
    const Scene& scene;
    const SceneAccel& accel;
    const Materials& materials;
    const DirectLighting& lighting;
    Stats& stats;
    ProgressSink* progress;  ///< carries the cancel token (null: no progress, no cancel)
    const CancelToken* cancel;
    /// The processes the frame is spread over (an MPI job's ranks, or this process alone):
    /// visibility, gathering, refinement and shading split their work among them.
    Communicator& comm;
};

/// The deep buffers of a frame: the gathered window (the window and its margin) and the
/// shaded window inside it.
struct VisibilityResult {
    DeepBuffer gathered;             ///< the window the passes gather in
    std::optional<DeepBuffer> crop;  ///< a crop's own window, when it differs from `gathered`
    /// The fragments the shading pass shades (the crop, or the gathered window itself).
    const DeepBuffer& shaded() const { return crop ? *crop : gathered; }
};
/// Traces, reads or takes over the previous frame's deep buffer, as the plan says (plan.deep_out
/// is written by the front end, with the frame's other outputs).
VisibilityResult visibility_pass(const FrameContext& ctx, const FramePlan& plan, const FrameState& previous);

/// Radiosity textures as the plan says (null for RadiosityStep::None), and for a carried one
/// where its radiosity changed since the previous frame.
struct RadiosityResult {
    std::unique_ptr<RadiosityTextures> textures;
    std::vector<LightChange> changed;
    float brightest = 0;  ///< the largest radiance a moving object may show or hide (temporal.h)
};
RadiosityResult radiosity_pass(const FrameContext& ctx, const FramePlan& plan, const FrameState& previous);

/// The cache a frame starts from (null when the plan has none).
struct CacheStartResult {
    std::unique_ptr<IrradianceCache> cache;
    size_t records_loaded = 0;
    std::vector<std::string> differences;  ///< settings that differ from a reused file's (cache_reuse Any)
    bool other_lighting = false;           ///< the file's records hold other lights' bounce light
    TemporalJudgement judged;              ///< CacheStart::Temporal: what became of the previous frame's records
};
CacheStartResult cache_start_pass(const FrameContext& ctx, const FramePlan& plan, const FrameState& previous,
                                  const RadiosityResult& radiosity);
/// Under MPI: every process takes the sides the others baked (RadiosityTextures::take_baked).
void share_radiosity_pass(const FrameContext& ctx, RadiosityTextures& rt);
/// Saves radiosity textures that this frame baked into render.radiosity_textures.
void save_radiosity_pass(const FrameContext& ctx, const RadiosityTextures& rt, size_t baked_before);

/// What mirrors and glass show in the shaded window: the surfaces where their paths end
/// (specular.h: sites, as fragments; empty when the scene has no mirror or glass) and, under
/// brute force, the gather at each.
struct SpecularSitesResult {
    bool mirrors = false;  ///< the scene has mirrors or glass (sites are traced only when gathers light them)
    DeepBuffer sites;
    std::vector<Indirect> brute;
    bool any() const { return !sites.fragments.empty(); }
    /// Whether the cache (or brute force) lights the sites: indirect_at_specular_hits = cache.
    static bool lit_by_gathers(const Scene& scene);
};
SpecularSitesResult specular_sites_pass(const FrameContext& ctx, const FramePlan& plan, const DeepBuffer& shaded);
/// The sites' part of the gathering pass: records where the cache does not cover a site.
/// Returns how many it made.
size_t specular_gather_pass(const FrameContext& ctx, const FramePlan& plan, const DeepBuffer& sites, const Gatherer& gatherer,
                            IrradianceCache& cache);
/// Brute force: a gather at every site (into `specular.brute`).
void specular_brute_pass(const FrameContext& ctx, const Gatherer& gatherer, SpecularSitesResult& specular);
/// The light the shading pass gives a window's sites: the cache's interpolation (its misses
/// counted), brute force's gathers, or the radiosity textures.
struct SiteLightResult {
    DeepBuffer sites;  ///< the window's own (a tile of the frame's)
    std::vector<Indirect> light;
    bool has_light = false;
    const RadiosityTextures* radiosity = nullptr;
    size_t misses = 0;
    SiteLight view() const { return {sites.offsets.empty() ? nullptr : &sites, has_light ? &light : nullptr, radiosity}; }
};
SiteLightResult site_light_for(const FrameContext& ctx, const SpecularSitesResult& specular, const std::array<int, 4>& window,
                               const IrradianceCache* cache, const RadiosityTextures* radiosity);

/// What the gathering pass made.
struct GatherPassResult {
    size_t records_new = 0;               ///< records in the cache that it did not start with (new and redone)
    size_t fragment_records_new = 0;      ///< per-fragment refinement's gathers
    size_t site_records_new = 0;          ///< records made for the sites of mirrors and glass (in records_new too)
    size_t regathered = 0, reshaded = 0;  ///< stale records of earlier frames redone
    std::vector<Record> waiting;          ///< stale records no fragment needed (for the next frame)
    std::vector<Record> gathers;          ///< refinement's gathers that still serve (plan.keep_gathers)
};
/// The gathering pass (and refinement) into `cache`, redoing the judged stale records where
/// they are needed; `preview`, if set, gets an image after each sub-pass.
GatherPassResult cache_gather_pass(const FrameContext& ctx, const FramePlan& plan, const VisibilityResult& deep,
                                   const RadiosityTextures* radiosity, IrradianceCache& cache, TemporalJudgement judged,
                                   const std::function<void(const Image&)>& preview, const SpecularSitesResult& specular);
/// A gather at every fragment of the shaded window (and at every site of `specular`).
std::vector<Indirect> brute_gather_pass(const FrameContext& ctx, const DeepBuffer& deep, const RadiosityTextures* radiosity,
                                        SpecularSitesResult& specular);

/// The shading pass: the image of the shaded window.
struct ShadeResult {
    Image image;
    size_t shading_misses = 0;   ///< fragments no record covered (left black)
    std::vector<float> refined;  ///< per pixel: the coverage of fragments that used their own record
    std::vector<Color> colours;  ///< render.deep_colour: what each fragment adds to the beauty (shade's `colours`)
};
/// Shades `deep` with the cache's interpolation (cache non-null), `brute` light (non-null) or
/// direct light only. With a cache and `quick_look`, first calls it with every 4th pixel
/// shaded standing for its 4x4 block (a re-shade's preview).
/// `specular`: the frame's sites (lit as site_light_for says; `radiosity` for
/// indirect_at_specular_hits = radiosity).
ShadeResult shading_pass(const FrameContext& ctx, const DeepBuffer& deep, const IrradianceCache* cache, const std::vector<Indirect>* brute,
                         const SpecularSitesResult& specular, const RadiosityTextures* radiosity,
                         const std::function<void(const Image&)>& quick_look = {});

/// The scene's gather settings for this frame's gathers: with gradients (`record_terms`) for
/// records, without for brute force, refinement and the correction; the frame's cancel token.
GatherSettings frame_gather_settings(const FrameContext& ctx, bool record_terms);

/// A copy of `cache` that a frame may add records to.
std::unique_ptr<IrradianceCache> copy_cache(const IrradianceCache& cache, const Scene& scene);

}  // namespace bounce
