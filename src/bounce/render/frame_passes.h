// The passes of a frame as the plan runs them. Every pass receives the one FrameContext
// (scene, BVHs, materials, lights, stats, progress, cancel) and its step of the plan (what it
// is to do, decided by plan_frame), and returns a typed result; run_frame (render.h) calls
// them in the plan's order and nothing else does: no pass calls a pass.
#pragma once

#include <memory>
#include <optional>
#include <vector>

#include "bounce/accel/accel.h"
#include "bounce/cache/irradiance_cache.h"
#include "bounce/cache/passes.h"
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
    const FramePlan& plan;  ///< the settings each pass takes (never the scene's)
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
/// Traces, reads or takes over the previous frame's deep buffer, as the step says, over the
/// plan's windows (plan.deep_out is written by the front end, with the frame's other outputs).
VisibilityResult visibility_pass(const FrameContext& ctx, const VisibilityStep& step, const FramePlan& plan, const FrameState& previous);

/// Radiosity textures as the step says, and for a carried one where its radiosity changed
/// since the previous frame.
struct RadiosityResult {
    std::unique_ptr<RadiosityTextures> textures;
    std::vector<LightChange> changed;
    float brightest = 0;  ///< the largest radiance a moving object may show or hide (temporal.h)
};
RadiosityResult radiosity_pass(const FrameContext& ctx, const RadiosityStep& step, const FramePlan& plan, const FrameState& previous);

/// The cache a frame starts from (null when the plan has none).
struct CacheStartResult {
    std::unique_ptr<IrradianceCache> cache;
    size_t records_loaded = 0;
    std::vector<std::string> differences;  ///< settings that differ from a reused file's (cache_reuse Any)
    bool other_lighting = false;           ///< the file's records hold other lights' bounce light
    TemporalJudgement judged;              ///< CacheStart::Temporal: what became of the previous frame's records
};
CacheStartResult cache_start_pass(const FrameContext& ctx, const CacheStartStep& step, const FramePlan& plan, const FrameState& previous,
                                  const RadiosityResult& radiosity);
/// After the last pass that may bake: the sides exchanged among an MPI job's ranks and saved
/// (by rank 0) as the step says; `baked_before`: the sides baked before the frame's gathers.
void finish_radiosity_pass(const FrameContext& ctx, const FinishRadiosityStep& step, RadiosityTextures& rt, size_t baked_before);

/// What mirrors and glass show in the shaded window: the surfaces where their paths end
/// (specular.h: sites, as fragments) and, under brute force, the gather at each. Empty
/// without a SpecularSitesStep.
struct SpecularSitesResult {
    DeepBuffer sites;
    std::vector<Indirect> brute;
    bool any() const { return !sites.fragments.empty(); }
};
SpecularSitesResult specular_sites_pass(const FrameContext& ctx, const SpecularSitesStep& step, const DeepBuffer& shaded);
/// The light the shading pass gives a window's sites: the cache's interpolation (its misses
/// counted), brute force's gathers, or the radiosity textures, as `from` says.
struct SiteLightResult {
    DeepBuffer sites;  ///< the window's own (a tile of the frame's)
    std::vector<Indirect> light;
    bool has_light = false;
    const RadiosityTextures* radiosity = nullptr;
    size_t misses = 0;
    SiteLight view() const { return {sites.offsets.empty() ? nullptr : &sites, has_light ? &light : nullptr, radiosity}; }
};
SiteLightResult site_light_for(const FrameContext& ctx, SiteLightFrom from, const SpecularSitesResult& specular,
                               const std::array<int, 4>& window, const IrradianceCache* cache, const RadiosityTextures* radiosity);

/// What the gathering steps made.
struct GatherPassResult {
    size_t records_new = 0;               ///< records in the cache that it did not start with (new and redone)
    size_t fragment_records_new = 0;      ///< per-fragment refinement's gathers
    size_t regathered = 0, reshaded = 0;  ///< stale records of earlier frames redone
    std::vector<Record> waiting;          ///< stale records no fragment needed (for the next frame)
    std::vector<Record> gathers;          ///< refinement's gathers that still serve (RefineStep::keep_gathers)
    SubPassCallback after_subpass;        ///< the preview after each sub-pass (GatherRecordsStep::preview)
};
/// The gathering pass into `cache`, redoing the judged stale records (taken from `judged`)
/// where they are needed; `preview`, if the step asks, gets an image after each sub-pass.
GatherPassResult record_gather_pass(const FrameContext& ctx, const GatherRecordsStep& step, const FramePlan& plan,
                                    const VisibilityResult& deep, const RadiosityTextures* radiosity, IrradianceCache& cache,
                                    TemporalJudgement& judged, const std::function<void(const Image&)>& preview);
/// Per-fragment refinement over the shaded window: the fragments' own gathers (their earlier
/// frames' taken from `judged`) into `cache`; `gathered` gets what it made.
void refine_pass(const FrameContext& ctx, const RefineStep& step, const FramePlan& plan, const VisibilityResult& deep,
                 const RadiosityTextures* radiosity, IrradianceCache& cache, TemporalJudgement& judged, GatherPassResult& gathered);
/// Records where the cache does not cover the sites of mirrors and glass. Returns how many it made.
size_t site_gather_pass(const FrameContext& ctx, const GatherSitesStep& step, const FramePlan& plan, const DeepBuffer& sites,
                        const RadiosityTextures* radiosity, IrradianceCache& cache);
/// A gather at every fragment of the shaded window (and, as the step says, at every site of
/// `specular`, into `specular.brute`).
std::vector<Indirect> brute_gather_pass(const FrameContext& ctx, const BruteGatherStep& step, const DeepBuffer& deep,
                                        const RadiosityTextures* radiosity, SpecularSitesResult& specular);

/// The shading pass: the image of the shaded window.
struct ShadeResult {
    Image image;
    size_t shading_misses = 0;   ///< fragments no record covered (left black)
    std::vector<float> refined;  ///< per pixel: the coverage of fragments that used their own record
    std::vector<Color> colours;  ///< render.deep_colour: what each fragment adds to the beauty (shade's `colours`)
};
/// Shades `deep` with the light the step names: the cache's interpolation (of `cache`), `brute`
/// or direct light only. With the step's quick look, first calls `quick_look` with every 4th
/// pixel shaded standing for its 4x4 block (a re-shade's preview).
/// `specular`: the frame's sites (lit as site_light_for says; `radiosity` for
/// indirect_at_specular_hits = radiosity).
ShadeResult shading_pass(const FrameContext& ctx, const ShadeStep& step, const DeepBuffer& deep, const IrradianceCache* cache,
                         const std::vector<Indirect>* brute, const SpecularSitesResult& specular, const RadiosityTextures* radiosity,
                         const std::function<void(const Image&)>& quick_look);

/// The plan's gather settings for this frame's gathers: with gradients (`record_terms`, and
/// the Hessian's terms with `hessian`) for records, without for brute force, refinement and the
/// correction; the frame's cancel token.
GatherSettings frame_gather_settings(const FrameContext& ctx, bool record_terms, bool hessian = false);

/// A copy of `cache` that a frame may add records to.
std::unique_ptr<IrradianceCache> copy_cache(const IrradianceCache& cache, const Scene& scene);

}  // namespace bounce
