// The render driver: visibility (or a loaded deep file), the gathering pass, the shading pass,
// on a TBB arena of the requested size, with statistics, progress and cancellation. Front ends
// (the CLI, the lighting tool) are thin layers over it: they ask for a frame, a sub-viewport
// (the scene's crop), a re-shade (cache_in) or a re-gather (regather), never run a pass.
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
#include "bounce/scene/scene.h"

namespace bounce {

struct RenderRequest {
    std::string deep_in;   ///< start from this deep file instead of tracing visibility
    /// Or from this deep buffer in memory (the lighting tool keeps its frame's); named
    /// deep_in in errors.
    std::shared_ptr<const DeepBuffer> deep;
    std::string deep_out;  ///< write the deep buffer (of the gathered window) here
    /// Preview mode (render.preview with gi cache): called with the whole image after every
    /// sub-pass, pixelated first and finer after; a shading-only re-shade calls it once, with
    /// every 4th pixel in x and y shaded and standing for its 4x4 block, before shading the rest.
    std::function<void(const Image&)> preview;
    std::string cache_in;   ///< start the irradiance cache from this file (gathers only where it misses)
    bool regather = false;  ///< flush the cache before gathering; with a crop and cache_in, only
                            ///< the records seen inside the crop are flushed
    bool force = false;     ///< accept a cache made for another scene or camera
    /// With cache_in and gi cache: shade the loaded cache as it is, with no gathering or
    /// refinement pass (an interactive re-shade). Where it lacks records the shading pass
    /// counts "shading_misses"; the caller gathers then.
    bool shade_only = false;
    /// With shade_only: shade this cache (in memory, never modified) instead of loading cache_in.
    std::shared_ptr<const IrradianceCache> shade_cache;
    CacheReuse cache_reuse = CacheReuse::Strict;  ///< keep a cache made with other settings
    int frame = 0;          ///< frame number stamped on new records (sequences)
    const CancelToken* cancel = nullptr;  ///< stops the render (throws Cancelled) when set
};

struct RenderResult {
    Image image;   ///< the shaded window (the crop, or the full frame)
    DeepBuffer deep;  ///< its fragments
    std::unique_ptr<IrradianceCache> cache;  ///< gi cache, or a loaded cache_in
    CacheFileInfo cache_info;                ///< the header a cache file of it carries
    size_t records_loaded = 0, records_new = 0;
};

/// Renders `scene`. Throws InputError on bad input (deep file from another scene ...) and
/// Cancelled when the request's token is set. With a crop, the gathering pass covers the crop
/// and a margin as wide as the largest record reach, so a crop's edges match a full render.
RenderResult render(const Scene& scene, const RenderRequest& request, Stats& stats, ProgressSink* progress);

/// Pixels outside the crop a margin gathers in: records reach at most max_spacing pixels
/// (times shading_reach in the shading pass).
int crop_margin(const Scene& scene);

/// The full frame: `base` (an earlier render of the whole frame) with `window` pasted over it,
/// layer by layer. InputError(base_name) if the base has another size or lacks a layer.
Image paste_over(const Image& base, const Image& window, const std::string& base_name);

/// Checks that a deep buffer belongs to `scene` and that its ids are in range.
void validate_deep_for_scene(const DeepBuffer& deep, const Scene& scene, const std::string& path);

/// Rough bytes a render of `scene` holds at once (deep buffer, image layers, per-fragment
/// light); render() refuses a frame whose estimate exceeds the memory available.
double estimate_render_bytes(const Scene& scene);

}  // namespace bounce
