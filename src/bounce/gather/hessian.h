// The translational Hessian of irradiance from one gather (Schwarzhaupt, Jensen and Jarosz,
// "Practical Hessian-based error control for irradiance caching", TOG 31(6), 2012; the form
// Radiance's ambient code uses since 4.2). The gather's hit points, joined in the order of the
// stratified grid, are a closed mesh of triangles around the gather point; each triangle is a
// polygon of uniform radiance (the value of its farthest vertex: what lies behind an occluding
// edge, the occlusion-aware variant), whose irradiance Hessian with respect to moving the
// receiver has a closed form summed over the polygon's edges. docs/irradiance-cache.md has the
// formulas.
#pragma once

#include <span>
#include <vector>

#include "bounce/core/math.h"
#include "bounce/core/scratch.h"

namespace bounce {

/// The Hessian of relative irradiance (irradiance over its mean, so 1/length^2) restricted to
/// the tangent plane, as principal curvatures and directions.
struct TangentHessian {
    Vec3 axis{0};              ///< unit tangent direction of the slower change (the long axis); 0 = none
    float slow = 0, fast = 0;  ///< |eigenvalues| along `axis` and across it (fast >= slow)
};

/// `points`: the hit point of every cell of an M x N (elevation x azimuth) grid, row-major;
/// `values`: their radiance (any positive scale); `dist`: their distances from `p`.
/// Rows run outwards from the normal, columns around it; the cells inside the first row close
/// the mesh as one polygon.
TangentHessian gather_hessian(const Vec3& p, const Vec3& n, int M, int N, std::span<const Vec3> points, std::span<const double> values,
                              std::span<const float> dist, ScratchBuffer& scratch);

}  // namespace bounce
