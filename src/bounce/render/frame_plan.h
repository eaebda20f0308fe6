// A frame as a plan (docs/architecture.md, "A frame is a plan"): built once from the scene at the
// frame's time, what the previous frame left (FrameState) and the front end's request, it says
// which passes run and on what. The CLI, a sequence, the lighting tool and an MPI rank all
// drive frames through it; a new capability adds a step or a plan rule, never a flag.
#pragma once

#include <array>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "bounce/cache/cache_identity.h"
#include "bounce/core/image.h"
#include "bounce/core/progress.h"
#include "bounce/deep/deep_buffer.h"
#include "bounce/scene/changes.h"
#include "bounce/scene/scene.h"

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
    std::shared_ptr<const std::vector<Record>> gathers;  ///< refinement's gathers that still serve (plan.keep_gathers)
    const std::vector<Record>& waiting_records() const { return waiting ? *waiting : none(); }
    const std::vector<Record>& kept_gathers() const { return gathers ? *gathers : none(); }

  private:
    static const std::vector<Record>& none() {
        static const std::vector<Record> empty;
        return empty;
    }
};

/// Primary visibility.
enum class VisibilityStep : uint8_t {
    Trace,     ///< trace the fine tessellation (a new deep buffer)
    ReadFile,  ///< read plan.deep_in
    Previous,  ///< the previous frame's deep buffer, in memory
};
/// The ray-tracing structures.
enum class AccelStep : uint8_t {
    Build,
    Keep,    ///< the previous frame's: nothing rays or the camera see has moved
    Update,  ///< built from the previous frame's: unchanged parts taken over, movers placed, skins refit
};
/// Radiosity textures for the gather's hits.
enum class RadiosityStep : uint8_t {
    None,       ///< no gather, AO, or render.radiosity off: hits are shaded with shadow rays
    Bake,       ///< laid out and baked lazily as rays hit them
    BakeSplit,  ///< an MPI job's still: every side baked at once, a share per rank, and exchanged
    Load,       ///< from render.radiosity_textures (baked lazily where the folder does not match)
    Carry,      ///< the previous frame's, re-baked where its direct light may have changed
};
/// Where the irradiance cache starts.
enum class CacheStart : uint8_t {
    None,  ///< no cache (brute force, direct only)
    Empty,
    File,      ///< plan.cache_in (with the identity checks of load_cache)
    Previous,  ///< the previous frame's cache, in memory, as it is
    Temporal,  ///< the previous frame's records judged for this frame: kept, moved or redone (temporal.h)
};
/// Which gathering runs.
enum class GatherStep : uint8_t {
    None,          ///< direct light only, or shade the starting cache (a re-shade)
    Brute,         ///< a gather at every fragment
    Cache,         ///< gathering pass (and refinement) where the starting cache misses
    WhereMissing,  ///< shade the starting cache; only if a fragment has no record, gather and shade again
};

struct FramePlan {
    int frame = 0;
    std::array<int, 4> window{};         ///< pixels shaded: the crop or the frame (x0, x1, y0, y1)
    std::array<int, 4> gather_window{};  ///< pixels gathered in: the window and its margin
    VisibilityStep visibility = VisibilityStep::Trace;
    std::string deep_in, deep_out;
    AccelStep accel = AccelStep::Build;
    RadiosityStep radiosity = RadiosityStep::None;
    /// An MPI job's ranks exchange the sides each baked: textures saved by rank 0, or carried to
    /// a shot's next frame, whose list of changed sides must be the same on every rank.
    bool share_radiosity = false;
    CacheStart cache = CacheStart::None;
    std::string cache_in;
    bool flush_crop = false;  ///< leave out the starting cache's records seen inside the crop
    bool force = false;
    CacheReuse cache_reuse = CacheReuse::Strict;
    /// Mirror and glass paths traced from the visible fragments to the sites where gathers
    /// light them (a scene with specular materials whose bounce light comes from gathers).
    bool specular_sites = false;
    GatherStep gather = GatherStep::None;
    bool refine = false;        ///< per-fragment refinement after the gathering pass
    bool correct = false;       ///< every fragment's own rays correct the records' prediction (cache.correction_rays)
    bool keep_hits = false;     ///< records keep their gather's hits: the shot's lights change, re-shading is cheaper
    bool keep_gathers = false;  ///< refinement's gathers are kept for the next frames to reuse (EarlierGathers)
    bool preview = false;       ///< progressive images through the request's callback
    int threads = 1;
    /// Frames of a shot: what changed since the previous frame (null otherwise).
    std::shared_ptr<const SceneChanges> changes;

    /// The plan as JSON (in --stats-json and the tool's status): one entry per step.
    nlohmann::json describe() const;
};

/// The plan of one frame. Throws InputError when the request cannot be met (a re-shade with
/// nothing to start from, a crop outside the previous deep buffer ...).
FramePlan plan_frame(const Scene& scene, const FrameState& previous, const RenderRequest& request);

/// Pixels outside the crop a margin gathers in: records reach at most max_spacing pixels
/// (times shading_reach in the shading pass).
int crop_margin(const Scene& scene);

}  // namespace bounce
