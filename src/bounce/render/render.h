// The render driver: visibility (or a loaded deep file), then the shading pass, on a TBB
// arena of the requested size, with statistics and progress. The CLI is a thin layer over it.
#pragma once

#include <functional>
#include <string>

#include <nlohmann/json.hpp>

#include "bounce/cache/cache_file.h"
#include "bounce/core/image.h"
#include "bounce/core/progress.h"
#include "bounce/core/stats.h"
#include "bounce/deep/deep_buffer.h"
#include "bounce/scene/scene.h"

namespace bounce {

struct RenderRequest {
    std::string deep_in;   ///< start from this deep file instead of tracing visibility
    std::string deep_out;  ///< write the deep buffer here
    /// Preview mode (render.preview with gi cache): called with the whole image after every
    /// sub-pass, pixelated first and finer after.
    std::function<void(const Image&)> preview;
    std::string cache_in;   ///< start the irradiance cache from this file (gathers only where it misses)
    std::string cache_out;  ///< write the irradiance cache here
    bool regather = false;  ///< flush the cache before gathering (ignore cache_in's records)
    bool force = false;     ///< accept a cache made for another scene or camera
    int frame = 0;          ///< frame number stamped on new records (sequences)
};

struct RenderResult {
    Image image;
    DeepBuffer deep;
    size_t records_loaded = 0, records_new = 0;
};

/// The header information a cache made for `scene` carries.
CacheFileInfo cache_file_info(const Scene& scene, int frame);

/// Renders `scene`. Throws InputError on bad input (deep file from another scene ...).
RenderResult render(const Scene& scene, const RenderRequest& request, Stats& stats,
                    ProgressSink* progress);

struct RadiositySettings;
struct CacheSettings;
/// The irradiance-cache settings a scene's render settings ask for.
CacheSettings cache_settings(const Scene& scene);
/// The radiosity-texture settings a scene's render settings ask for.
RadiositySettings radiosity_settings(const Scene& scene);

/// Adds a "records" layer: the beauty at half brightness with each record's position as a
/// white 3x3 dot.
void add_records_layer(Image& image, const Camera& camera, const std::vector<Vec3>& positions);

/// The seed's table (TL04 class notes): gathering, shading, total, rays per record, records,
/// rays per megapixel (millions) — a header line and one row, from Stats::to_json().
std::string seed_table(const nlohmann::json& stats);

/// Checks that a deep buffer belongs to `scene` and that its ids are in range.
void validate_deep_for_scene(const DeepBuffer& deep, const Scene& scene, const std::string& path);

}  // namespace bounce
