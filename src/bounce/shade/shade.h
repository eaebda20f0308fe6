// The shading pass: turns the fragments of a deep buffer into image layers. Direct lighting
// (with shadows) for every fragment; later stages add indirect light from gathering or the
// irradiance cache.
#pragma once

#include "bounce/core/image.h"
#include "bounce/core/progress.h"
#include "bounce/core/stats.h"
#include "bounce/deep/deep_buffer.h"
#include "bounce/lighting/lighting.h"

namespace bounce {

/// Layers: beauty (R,G,B,A), direct, albedo, N, depth (Z). Tiles run in parallel; the result
/// is independent of thread count and tile order.
Image shade(const Scene& scene, const DeepBuffer& deep, const Materials& materials,
            const DirectLighting& lighting, Stats& stats, ProgressSink* progress);

/// The random stream of fragment `k` of full-image pixel (x, y).
RandomStream fragment_stream(uint64_t seed, int x, int y, uint32_t k);

}  // namespace bounce
