// Surface reflection: a Lambertian lobe plus an optional GGX glossy lobe, and the model that
// lets such a BRDF consume cached irradiance as (radiance, direction) pairs
// (docs/shading.md; ic-algorithms.md 3.6).
#pragma once

#include <array>

#include "bounce/core/math.h"
#include "bounce/gather/gather.h"
#include "bounce/lighting/materials.h"

namespace bounce {

/// GGX (Trowbridge-Reitz) microfacet lobe f_s(wo, wi) about unit normal n, without the cosine:
/// D(alpha = roughness^2) x height-correlated Smith visibility x Schlick Fresnel from f0.
/// Zero when wo or wi is below the surface.
Color ggx_specular(const Vec3& n, const Vec3& wo, const Vec3& wi, const Color& f0, float roughness);

/// Radiance leaving a surface toward `wo` under cached indirect light `in`, looked up with the
/// un-bumped normal `n_lookup`. All of the light of a channel is assumed to arrive from one
/// direction d: the luminance-weighted mean incoming direction (one pair), or each channel's
/// own (three pairs, `per_channel`). The pair's radiance L = E / (n_lookup . d) makes a
/// Lambertian surface with the un-bumped normal get exactly albedo E / pi back; the shading
/// normal (bumped) and the glossy lobe then see light from d. When d grazes the surface
/// (n_lookup . d < 0.05) it carries no reliable direction and the light is taken along
/// n_lookup instead.
Color indirect_radiance(const Indirect& in, const Vec3& n_lookup, const SurfaceShading& s, const Vec3& wo, bool per_channel);

/// indirect_radiance's two lobes apart: their sum is indirect_radiance, bit for bit.
struct IndirectLobes {
    Color diffuse{0}, specular{0};
};
IndirectLobes indirect_lobes(const Indirect& in, const Vec3& n_lookup, const SurfaceShading& s, const Vec3& wo, bool per_channel);

}  // namespace bounce
