// The render driver: runs a frame's plan (frame_plan.h) — visibility or a deep buffer, the
// gathering pass, the shading pass — on a TBB arena of the requested size, with statistics,
// progress and cancellation. Front ends (the CLI, sequences, the lighting tool) are thin layers
// over it: they ask for a frame, a sub-viewport (the scene's crop), a re-shade or a re-gather,
// never run a pass.
#pragma once

#include <array>
#include <functional>
#include <memory>
#include <string>

#include "bounce/cache/cache_identity.h"
#include "bounce/core/image.h"
#include "bounce/core/progress.h"
#include "bounce/core/stats.h"
#include "bounce/deep/deep_buffer.h"
#include "bounce/render/frame_plan.h"
#include "bounce/scene/scene.h"

namespace bounce {

/// What became of the previous frame's records in a frame of a shot (temporal.h).
struct TemporalCounts {
    size_t kept = 0;                        ///< kept as they were
    size_t moved = 0;                       ///< travelled with their object (then gathered again where needed)
    size_t view = 0;                        ///< something in their view moved
    size_t light = 0;                       ///< only the light in their view changed
    size_t dropped = 0;                     ///< on a deforming object, or the objects changed
    size_t regathered = 0;                  ///< stale records gathered again in place
    size_t reshaded = 0;                    ///< stale records re-shaded from their hits (no ray traced)
    size_t anchored = 0, anchors_kept = 0;  ///< records on moving objects, and those that followed them
};

/// What a frame produced: its image and deep buffer, the cache it ended with, and what each
/// pass did (typed: front ends steer on these, never on stats).
struct RenderResult {
    FramePlan plan;   ///< the plan that ran
    Image image;      ///< the shaded window (the crop, or the full frame)
    DeepBuffer deep;  ///< its fragments
    /// The gathered window's deep buffer (the window and its margin) when the plan has a
    /// deep_out: the front end writes it with the frame's other outputs, at the end.
    std::shared_ptr<const DeepBuffer> gathered_deep;
    /// With render.deep_colour: what each of gathered_deep's fragments adds to the beauty (0
    /// outside the shaded window), for write_deep.
    std::vector<Color> deep_colour;
    std::unique_ptr<IrradianceCache> cache;  ///< gi cache, or a loaded cache_in
    CacheFileInfo cache_info;                ///< the header a cache file of it carries
    size_t records_loaded = 0, records_new = 0;
    size_t fragment_records_new = 0;  ///< per-fragment refinement's gathers made by this frame
    size_t shading_misses = 0;        ///< fragments no record covered (0 unless something is wrong)
    bool gathered = false;            ///< a gathering pass ran (a re-shade may not need one)
    /// Settings that differ from a reused cache file's (with CacheReuse::Any).
    std::vector<std::string> cache_differences;
    /// The loaded cache was gathered under other lights or materials: its bounce light is theirs.
    bool cache_other_lighting = false;
    TemporalCounts temporal;                  ///< CacheStart::Temporal
    std::shared_ptr<const SceneAccel> accel;  ///< for the next frame of a shot
    std::shared_ptr<const RadiosityTextures> radiosity;
    std::vector<Record> waiting;  ///< stale records no fragment needed
    std::vector<Record> gathers;  ///< refinement's gathers that still serve
    /// True when the cache differs from the one the frame started from.
    bool cache_changed() const { return records_new > 0 || fragment_records_new > 0 || plan.cache_start() == CacheStart::Empty; }
    /// What the next frame's plan may start from: moves the deep buffer and the cache out of
    /// this result into shared, immutable state.
    FrameState release_state();
};

/// Runs `plan` (plan_frame) on `scene`. Throws InputError on bad input (a deep file from
/// another scene ...) and Cancelled when the request's token is set.
RenderResult run_frame(const Scene& scene, const FramePlan& plan, const FrameState& previous, const RenderRequest& request, Stats& stats,
                       ProgressSink* progress);

/// A still: the plan of `request` with nothing from a previous frame, run; the deep file (if
/// asked for) written once it has finished. With a crop, the gathering pass covers the crop
/// and a margin as wide as the largest record reach, so a crop's edges match a full render.
RenderResult render(const Scene& scene, const RenderRequest& request, Stats& stats, ProgressSink* progress);

/// The full frame: `base` (an earlier render of the whole frame) with `window` pasted over it,
/// layer by layer. InputError(base_name) if the base has another size or lacks a layer.
Image paste_over(const Image& base, const Image& window, const std::string& base_name);

/// Checks that a deep buffer belongs to `scene` and that its ids are in range.
void validate_deep_for_scene(const DeepBuffer& deep, const Scene& scene, const std::string& path);

/// Rough bytes a render of window `w` ({x0, x1, y0, y1}) holds at once (deep buffer, image
/// layers, per-fragment light); the plan refuses a frame whose estimate exceeds the memory available.
double estimate_render_bytes(const std::array<int, 4>& w);

}  // namespace bounce
