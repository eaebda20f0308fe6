// The one way a texture read whole at load is looked up (opacity and emission maps): as
// OpenImageIO's periodic lookup of the colour texture, so every texture of a material lines up.
#pragma once

#include <cmath>
#include <cstddef>

#include "bounce/core/math.h"

namespace bounce {

/// Bilinear lookup at uv of a width x height image with periodic wrap: s = u, t = 1 - v, texel
/// centres at (i + 0.5) / width, row 0 at the top. `texel(x, y)` returns a texel's value (a
/// float or a Color); a uv that is not finite reads texel (0, 0).
template <class Texel>
auto periodic_bilinear(int width, int height, const Vec2& uv, Texel texel) {
    float x = uv.x * static_cast<float>(width) - 0.5f, y = (1 - uv.y) * static_cast<float>(height) - 0.5f;
    if (!std::isfinite(x) || !std::isfinite(y)) x = y = 0;
    const float fx = std::floor(x), fy = std::floor(y);
    const float ax = x - fx, ay = y - fy;
    const auto wrap = [](float i, int n) {
        const double m = std::fmod(static_cast<double>(i), static_cast<double>(n));
        return static_cast<size_t>(m < 0 ? m + n : m);
    };
    const size_t x0 = wrap(fx, width), x1 = wrap(fx + 1, width), y0 = wrap(fy, height), y1 = wrap(fy + 1, height);
    const auto top = texel(x0, y0) * (1 - ax) + texel(x1, y0) * ax;
    const auto bottom = texel(x0, y1) * (1 - ax) + texel(x1, y1) * ax;
    return top * (1 - ay) + bottom * ay;
}

}  // namespace bounce
