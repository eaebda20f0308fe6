// Guided per-fragment gathers (issue 47, route 3): a fragment's rays are spread over the
// hemisphere's 32 direction bins (direction_bin: equal cosine-weighted measure each) in
// proportion to how much each bin's radiance varied in a nearby pilot gather, rather than
// evenly. Every bin keeps at least one ray and a defensive share of them, and within a bin the
// rays stay stratified, so the estimate sum_b (pi / 32) mean_b(L) is unbiased whatever the
// guide says (Neyman allocation over strata; docs/gather.md, "Guided gathers"). Records keep
// the plain grid: their gradients are sums over its cells' boundaries.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "bounce/gather/gather.h"

namespace bounce {

/// What a pilot gather saw per direction bin of its frame: the spread of the radiance's
/// luminance (AO: of the unoccluded fraction) between neighbouring cells of the bin, an
/// estimate of the per-ray standard deviation a stratified gather meets there.
struct DirectionGuide {
    std::array<float, kReachBins> spread{};
    Vec3 n{0, 0, 1};  ///< the pilot's normal (its frame is Frame(n))
};

/// How many rays each bin takes: round(rays x ((1 - share) / 32 + share x spread_b / sum)),
/// at least one, summing to `rays` (largest remainders). `share` in [0, 1): the guided share;
/// a guide with no spread anywhere gives the even split.
std::array<int, kReachBins> guided_allocation(const DirectionGuide& guide, int rays, float share);

/// The rays of a guided gather in its frame (z = normal) and each one's share of the cosine-
/// weighted hemisphere (the weights sum to 1): bin b's n_b rays on a rows x columns grid of
/// its (sin^2 theta, phi) rectangle, jittered by `rng` (ray index i, kDimGather and +1).
struct GuidedRays {
    std::vector<Vec3> local;
    std::vector<float> weight;
};
void guided_rays(const std::array<int, kReachBins>& allocation, const RandomStream& rng, GuidedRays& out);

/// Brute force's guides (GatherSettings::guided > 0; gather_every_fragment): one pilot gather (of at
/// least kPilotRays rays) per kGuideBlock x kGuideBlock block of full-image pixels, at its centre pixel's first fragment that
/// takes bounce light, with its own random stream; a fragment's gather is guided by its block's
/// pilot when their normals agree within kGuideCos, plain otherwise.
inline constexpr int kGuideBlock = 8, kPilotRays = 1024;
inline constexpr float kGuideCos = 0.9f;

}  // namespace bounce
