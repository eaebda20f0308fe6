// A frame as a plan (docs/architecture.md, "A frame is a plan"): built once from the scene at the
// frame's time, what the previous frame left (FrameState) and the front end's request, it lists
// the steps that run, in order, each with its resolved configuration; run_frame is a loop over
// them. plan_frame is the only code that reads settings to decide what runs. The CLI, a
// sequence, the lighting tool and an MPI rank all drive frames through it; a new capability
// adds a step or a plan rule, never a flag.
#pragma once

#include <array>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <variant>
#include <vector>

#include "bounce/cache/cache_identity.h"
#include "bounce/config/settings.h"
#include "bounce/core/image.h"
#include "bounce/core/progress.h"
#include "bounce/deep/deep_buffer.h"
#include "bounce/gather/gather.h"
#include "bounce/scene/changes.h"
#include "bounce/scene/scene.h"
#include "bounce/shade/shade.h"

namespace bounce {

class Communicator;

/// What a front end asks of a frame, given what the frame before left (FrameState).
enum class FrameKind : uint8_t {
    /// The frame on its own: its deep buffer and cache from the request's files, or made anew.
    Still,
    /// The next frame of a shot (the previous state is the frame before in time): BVHs,
    /// radiosity texels, cache records and the deep buffer are kept, moved or redone by what
    /// changed between the two scenes (docs/animation.md). Also the first frame (no previous
    /// state): its records keep what the next frame reuses.
    ShotFrame,
    /// The previous frame's deep buffer and cache (in memory, else the request's files) shaded
    /// as they are; the gathering and refinement passes run only if a fragment has no record.
    Reshade,
    /// The previous frame's deep buffer (in memory, else deep_in); the cache flushed before
    /// gathering: with a crop and a cache to start from, only the records seen inside the crop.
    Regather,
};

/// What a front end asks of one frame.
struct RenderRequest {
    FrameKind kind = FrameKind::Still;
    std::string deep_in;   ///< start from this deep file instead of tracing visibility
    std::string deep_out;  ///< write the deep buffer (of the gathered window) here
    /// Write the deep buffer here when the frame traces a new one (the lighting tool's session
    /// file: a frame that keeps the last one has it on disk already). deep_out wins.
    std::string deep_out_if_traced;
    /// Preview mode (render.preview with gi cache): called with the whole image after every
    /// sub-pass, pixelated first and finer after; a re-shade calls it once, with every 4th
    /// pixel in x and y shaded and standing for its 4x4 block, before shading the rest.
    std::function<void(const Image&)> preview;
    std::string cache_in;                         ///< start the irradiance cache from this file (gathers only where it misses)
    bool force = false;                           ///< accept a cache made for another scene or camera
    CacheReuse cache_reuse = CacheReuse::Strict;  ///< keep a cache made with other settings
    int frame = 0;                                ///< frame number stamped on new records (sequences)
    const CancelToken* cancel = nullptr;          ///< stops the render (throws Cancelled) when set
    Communicator* comm = nullptr;                 ///< an MPI job's ranks the frame is spread over (null: this process)
};

class SceneAccel;
class RadiosityTextures;

/// What a finished frame leaves for the next plan: the frame window's deep buffer and the cache
/// as it ended (never modified afterwards; a plan that changes them makes copies), and for the
/// next frame of a shot its scene, BVHs, radiosity textures and the stale records no fragment
/// needed yet.
struct FrameState {
    std::shared_ptr<const DeepBuffer> deep;
    std::shared_ptr<const IrradianceCache> cache;
    std::shared_ptr<const Scene> scene;  ///< its meshes back `accel`
    std::shared_ptr<const SceneAccel> accel;
    std::shared_ptr<const RadiosityTextures> radiosity;
    /// Shared like the rest, so a front end that keeps the state (the lighting tool) hands it to
    /// the next plan without copying records (a shot's kept gathers hold their rays' hits).
    std::shared_ptr<const std::vector<Record>> waiting;
    std::shared_ptr<const std::vector<Record>> gathers;  ///< refinement's gathers that still serve (RefineStep::keep_gathers)
    const std::vector<Record>& waiting_records() const { return waiting ? *waiting : none(); }
    const std::vector<Record>& kept_gathers() const { return gathers ? *gathers : none(); }

  private:
    static const std::vector<Record>& none() {
        static const std::vector<Record> empty;
        return empty;
    }
};

/// When a step runs.
enum class RunWhen : uint8_t {
    Always,
    /// Only if the shading step before it left fragments no record covers: a re-shade gathers
    /// (and shades again) only where its starting cache misses.
    ShadingMissed,
};

/// Where the ray-tracing structures come from.
enum class AccelSource : uint8_t {
    Build,
    Keep,    ///< the previous frame's: nothing rays or the camera see has moved
    Update,  ///< built from the previous frame's: unchanged parts taken over, movers placed, skins refit
};
struct AccelStep {
    AccelSource source = AccelSource::Build;
    LightingSettings lighting;  ///< the ray offset, and the frame's direct lighting built with the BVHs
};

/// Where the frame's deep buffer comes from.
enum class DeepSource : uint8_t {
    Trace,     ///< trace the fine tessellation (a new deep buffer)
    ReadFile,  ///< read `deep_in`
    Previous,  ///< the previous frame's deep buffer, in memory
};
struct VisibilityStep {
    DeepSource source = DeepSource::Trace;
    VisibilitySettings settings;  ///< samples, seed and crop of a traced deep buffer
    std::string deep_in;
    bool crop = false;  ///< the shaded window is a crop of the gathered one
    /// Under MPI every rank keeps every tile's fragments (a crop's tiles differ from the gathered
    /// window's, or rank 0 writes the deep file), not only its own.
    bool every_tile = false;
};

/// Where the radiosity textures for the gathers' hits come from.
enum class RadiositySource : uint8_t {
    Bake,       ///< laid out and baked lazily as rays hit them
    BakeSplit,  ///< an MPI job's still: every side baked at once, a share per rank, and exchanged
    Load,       ///< from `folder` (baked lazily where the folder does not match)
    Carry,      ///< the previous frame's, re-baked where its direct light may have changed
};
/// Radiosity textures for the gathers' hits (without this step, hits are shaded with shadow rays).
struct RadiosityStep {
    RadiositySource source = RadiositySource::Bake;
    RadiositySettings settings;  ///< with light_parts as the records keep them
    std::string folder;          ///< render.radiosity_textures (Load)
};
/// After the last pass that may bake sides: MPI ranks exchange the sides each baked (textures
/// saved by rank 0, or carried to a shot's next frame, whose list of changed sides must be the
/// same on every rank), and the textures are saved to `folder` if it names one.
struct FinishRadiosityStep {
    bool share = false;
    std::string folder;
};

/// Where the irradiance cache starts.
enum class CacheStart : uint8_t {
    None,  ///< no cache (brute force, direct only): no step
    Empty,
    File,      ///< `cache_in` (with the identity checks of load_cache)
    Previous,  ///< the previous frame's cache, in memory, as it is
    Temporal,  ///< the previous frame's records judged for this frame: kept, moved or redone (temporal.h)
};
struct CacheStartStep {
    CacheStart start = CacheStart::Empty;
    bool ao = false;  ///< records of AO, not of irradiance
    std::string cache_in;
    bool flush_crop = false;  ///< leave out the starting cache's records seen inside the crop
    bool force = false;
    CacheReuse reuse = CacheReuse::Strict;
    bool light_parts = false;  ///< records keep per-light parts, scaled by today's lights
};

/// Mirror and glass paths traced from the visible fragments to the sites where gathers light
/// them (a scene with specular materials whose bounce light comes from gathers).
struct SpecularSitesStep {
    int depth = 0;  ///< bounces a path follows (render.specular_depth)
};

/// The gathering pass: records where fragments need them, earlier frames' stale records redone
/// where they are needed.
struct GatherRecordsStep {
    bool hessian = false;    ///< records carry the Hessian metric's terms
    int first_rays = 0;      ///< adaptive records: rays of a first estimate (0: every record gathers render.rays)
    float own_weight = 0;    ///< the weight at which one record covers a point alone (0: the settings')
    bool keep_hits = false;  ///< records keep their gather's hits: the shot's lights change, re-shading is cheaper
    bool preview = false;    ///< progressive images through the request's callback
    CacheSharing sharing = CacheSharing::Shared;
};
/// Per-fragment refinement where the records disagree.
struct RefineStep {
    int rays = 0;                 ///< of a refined fragment's own gather
    bool keep_rays = false;       ///< the gathers keep their hits (a shot: the next frames reuse them)
    bool keep_gathers = false;    ///< refinement's gathers kept for the next frames to reuse (EarlierGathers)
    bool refined_before = false;  ///< a moving camera's frame: the fragments refined the frame before keep their gathers (hysteresis)
    bool preview = false;
    float reuse = 0;  ///< keep_gathers: how far (pixels) an earlier gather lends its rays (render.temporal_refine_reuse)
};
/// Records where the cache does not cover the sites of mirrors and glass.
struct GatherSitesStep {
    bool hessian = false;
    bool keep_hits = false;
};
/// A gather at every fragment of the shaded window (and at every site of mirrors and glass).
struct BruteGatherStep {
    bool sites = false;
};

/// The light the shading step gives the fragments.
enum class IndirectFrom : uint8_t {
    None,   ///< direct light only
    Brute,  ///< brute force's gathers
    Cache,  ///< the cache's interpolation
};
/// The light the shading step gives the sites of mirrors and glass.
enum class SiteLightFrom : uint8_t {
    None,       ///< direct light only (or AO), traced by the shading pass
    Radiosity,  ///< the radiosity textures (render.indirect_at_specular_hits = radiosity)
    Cache,      ///< the cache's interpolation at the sites
    Brute,      ///< brute force's gathers at the sites
};
struct ShadeStep {
    IndirectFrom indirect = IndirectFrom::None;
    SiteLightFrom sites = SiteLightFrom::None;
    int correction_rays = 0;     ///< records as a control variate: every fragment's own rays correct their prediction
    bool per_light = false;      ///< per-light indirect layers from the records' light parts
    bool deep_colour = false;    ///< what each fragment adds to the beauty (render.deep_colour)
    bool quick_look = false;     ///< a re-shade's preview first: every 4th pixel shaded, standing for its 4x4 block
    bool refined_layer = false;  ///< the `refined` layer (refinement ran, or the cache holds fragments' own records)
};

using Step = std::variant<AccelStep, VisibilityStep, RadiosityStep, CacheStartStep, SpecularSitesStep, GatherRecordsStep, RefineStep,
                          GatherSitesStep, BruteGatherStep, ShadeStep, FinishRadiosityStep>;
struct PlannedStep {
    Step step;
    RunWhen when = RunWhen::Always;
};

struct FramePlan {
    int frame = 0;
    /// The settings the plan resolved for its passes, frame-wide; each step carries its own.
    /// Every gather's (steps set record_terms and hessian; AO distance resolved), and the one
    /// copy of the frame's seed and tiles (`gather.tiling`, which tiling() and shade() read).
    GatherSettings gather;
    CacheSettings cache;                 ///< the cache's: records, refinement, the temporal rules
    ShadingSettings shading;             ///< how light reaches the BRDF, which layers
    std::array<int, 4> window{};         ///< pixels shaded: the crop or the frame (x0, x1, y0, y1)
    std::array<int, 4> gather_window{};  ///< pixels gathered in: the window and its margin
    std::string deep_out;                ///< where the front end writes the gathered window's deep buffer
    int threads = 1;
    /// Frames of a shot: what changed since the previous frame (null otherwise).
    std::shared_ptr<const SceneChanges> changes;
    /// What runs, in order: run_frame is a loop over it.
    std::vector<PlannedStep> steps;

    /// The first step of type S, or null.
    template <class S>
    const S* find() const {
        for (const PlannedStep& s : steps)
            if (const S* p = std::get_if<S>(&s.step)) return p;
        return nullptr;
    }
    /// Every per-pixel pass's seed and tiles.
    const FrameTiling& tiling() const { return gather.tiling; }
    /// The shading pass's options (and the previews').
    ShadeOptions shade() const { return {gather.tiling, shading, gather.ao}; }
    /// The light the (last) shading step gives the fragments.
    IndirectFrom indirect() const {
        IndirectFrom out = IndirectFrom::None;
        for (const PlannedStep& s : steps)
            if (const ShadeStep* p = std::get_if<ShadeStep>(&s.step)) out = p->indirect;
        return out;
    }
    /// Where the cache starts (None without a cache step).
    CacheStart cache_start() const {
        const CacheStartStep* s = find<CacheStartStep>();
        return s ? s->start : CacheStart::None;
    }
    /// The plan as JSON (in --stats-json and the tool's status): the frame, its windows and one
    /// entry per step, in order.
    nlohmann::json describe() const;
};

/// The plan of one frame. Throws InputError when the request cannot be met (a re-shade with
/// nothing to start from, a crop outside the previous deep buffer ...).
FramePlan plan_frame(const Scene& scene, const FrameState& previous, const RenderRequest& request);

/// Pixels outside the crop a margin gathers in: records reach at most max_spacing pixels
/// (times shading_reach in the shading pass).
int crop_margin(const CacheSettings& settings);

}  // namespace bounce
