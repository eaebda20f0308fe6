// A gather's bounce light per light (render.light_parts): each light's part with its scale
// factored out, so a light's colour or intensity edit rescales records exactly.
#pragma once

#include <array>
#include <span>
#include <vector>

#include "bounce/core/math.h"

namespace bounce {

/// The part of a gather's (and its record's) values that is linear in the light: what one light (or all of them,
/// each at scale 1) contributes to its irradiance, directions and gradients.
struct LightPart {
    Color E{0};
    std::array<Vec3, 3> dir{}, grad_r{}, grad_t{};
};

/// A gather's bounce light per light (GatherSettings::light_parts), every light's scale
/// (light_scales) factored out; fixed once made, so records' copies share it.
struct LightParts {
    LightPart signal;              ///< every light at scale 1: what placement decisions read
    std::vector<LightPart> light;  ///< per scene light
    size_t bytes() const { return sizeof(LightParts) + light.size() * sizeof(LightPart); }
};

/// The sum of every light's part times its scale, in one fixed order (a record made fresh and
/// one rescaled to the same scales hold the same bits).
LightPart combine_parts(const LightParts& parts, std::span<const Color> scales);

/// Divides each channel of `parts` by the channel's sum over them (all 0 where the sum is not
/// positive): each light's share of a total.
void normalise_shares(std::span<Color> parts);

}  // namespace bounce
