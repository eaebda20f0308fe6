// Sample warps shared by every stage: stratified unit-square samples and the cosine-weighted
// hemisphere.
#pragma once

#include <cmath>

#include "bounce/core/math.h"

namespace bounce {

/// Stratified 2D sample `i` of `n` with jitter (jx, jy): a cell of the largest square grid
/// that fits in n; samples beyond it are uniform (jx, jy). Each part is unbiased, so the sum
/// over all n samples is too.
inline Vec2 stratified_2d(int i, int n, float jx, float jy) {
    int nx = std::max(1, static_cast<int>(std::sqrt(static_cast<float>(n))));
    if (i >= nx * nx) return {jx, jy};
    auto fn = static_cast<float>(nx);
    return {(static_cast<float>(i % nx) + jx) / fn, (static_cast<float>(i / nx) + jy) / fn};
}

/// Shirley-Chiu concentric map of the unit square onto the unit disc (area preserving, low
/// distortion): lens samples for depth of field.
inline Vec2 concentric_disc(float u, float v) {
    const float a = 2 * u - 1, b = 2 * v - 1;
    if (a == 0 && b == 0) return {0, 0};
    float r, phi;
    if (std::abs(a) > std::abs(b))
        r = a, phi = 0.25f * kPi * (b / a);
    else
        r = b, phi = 0.5f * kPi - 0.25f * kPi * (a / b);
    return {r * std::cos(phi), r * std::sin(phi)};
}

/// Cosine-weighted direction in the local frame (z up) from a unit-square sample
/// (pdf cos(theta)/pi).
inline Vec3 cosine_hemisphere(float u1, float u2) {
    float r = std::sqrt(u1), phi = 2 * kPi * u2;
    return {r * std::cos(phi), r * std::sin(phi), std::sqrt(std::max(0.0f, 1 - u1))};
}

}  // namespace bounce
