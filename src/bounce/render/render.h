// The render driver: visibility (or a loaded deep file), then the shading pass, on a TBB
// arena of the requested size, with statistics and progress. The CLI is a thin layer over it.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "bounce/core/image.h"
#include "bounce/core/progress.h"
#include "bounce/core/stats.h"
#include "bounce/deep/deep_buffer.h"
#include "bounce/scene/scene.h"

namespace bounce {

struct RenderRequest {
    std::string deep_in;   ///< start from this deep file instead of tracing visibility
    std::string deep_out;  ///< write the deep buffer here
};

struct RenderResult {
    Image image;
    DeepBuffer deep;
};

/// Renders `scene`. Throws InputError on bad input (deep file from another scene ...).
RenderResult render(const Scene& scene, const RenderRequest& request, Stats& stats,
                    ProgressSink* progress);

struct RadiositySettings;
/// The radiosity-texture settings a scene's render settings ask for.
RadiositySettings radiosity_settings(const Scene& scene);

/// The seed's table (TL04 class notes): gathering, shading, total, rays per record, records,
/// rays per megapixel (millions) — a header line and one row, from Stats::to_json().
std::string seed_table(const nlohmann::json& stats);

/// Checks that a deep buffer belongs to `scene` and that its ids are in range.
void validate_deep_for_scene(const DeepBuffer& deep, const Scene& scene, const std::string& path);

}  // namespace bounce
