// Baked ambient occlusion in an object's uv space: what the cache misses on a displaced
// surface (self-occlusion by detail smaller than the record spacing, which the coarse ray
// tessellation does not even hold) is mostly static, so it is gathered once per texel against
// the fine, displaced surface and multiplied into the cached light by a material's
// `ao_texture` (docs/displacement.md).
#pragma once

#include <cstdint>
#include <vector>

#include "bounce/accel/accel.h"
#include "bounce/core/progress.h"
#include "bounce/core/stats.h"
#include "bounce/scene/scene.h"

namespace bounce {

struct AoBakeSettings {
    int resolution = 1024;  ///< texels per side of the uv square
    int rays = 256;         ///< cosine-weighted rays per texel
    float distance = 0;     ///< occluders farther than this do not count (> 0)
};

/// Unoccluded fraction (cosine-weighted, 1 = open) per texel of object `id`'s uv square, row 0
/// at the top (v = 1), against every object's fine surface; texels no triangle covers take
/// their nearest covered neighbour's value within 4 texels (so filtering at uv seams does not
/// pull in black), else 1. Throws InputError naming `scene.path` when the object has no uvs.
std::vector<float> bake_ao(const Scene& scene, const SceneAccel& accel, uint32_t id, const AoBakeSettings& settings, Stats& stats,
                           ProgressSink* progress);

}  // namespace bounce
