#include "bounce/shade/brdf.h"

#include <algorithm>
#include <cmath>

namespace bounce {

Color ggx_specular(const Vec3& n, const Vec3& wo, const Vec3& wi, const Color& f0, float roughness) {
    const float no = dot(n, wo), ni = dot(n, wi);
    if (no <= 0 || ni <= 0) return Color(0);
    Vec3 h = wo + wi;
    if (dot(h, h) <= 0) return Color(0);
    h = normalize(h);
    const float a = roughness * roughness, a2 = a * a;
    const float nh = std::max(dot(n, h), 0.0f);
    const float t = nh * nh * (a2 - 1) + 1;
    const float D = a2 / (kPi * t * t);
    const float V = 0.5f / (ni * std::sqrt(no * no * (1 - a2) + a2) + no * std::sqrt(ni * ni * (1 - a2) + a2));
    const float fw = std::pow(1 - std::clamp(dot(wo, h), 0.0f, 1.0f), 5.0f);
    const Color F = f0 + (Color(1) - f0) * fw;
    return F * (D * V);
}

namespace {

/// Outgoing radiance (diffuse and glossy lobes) for irradiance E (per channel, masked by the
/// caller) arriving along the unnormalised mean direction D.
IndirectLobes one_pair(const Color& E, const Vec3& D, const Vec3& n_lookup, const SurfaceShading& s, const Vec3& wo) {
    Vec3 d = n_lookup;
    float cos_lookup = dot(n_lookup, n_lookup);
    if (dot(D, D) > 0) {
        const Vec3 dn = normalize(D);
        const float c = dot(n_lookup, dn);
        if (c >= 0.05f) d = dn, cos_lookup = c;
    }
    // The ratio is exactly 1 when the shading normal is the lookup normal: no energy change.
    const float ratio = std::max(dot(s.normal, d), 0.0f) / cos_lookup;
    IndirectLobes out;
    out.diffuse = s.albedo * E * (kInvPi * ratio);
    if (s.specular.x > 0 || s.specular.y > 0 || s.specular.z > 0)
        out.specular = ggx_specular(s.normal, wo, d, s.specular, s.roughness) * E * ratio;
    return out;
}

}  // namespace

IndirectLobes indirect_lobes(const Indirect& in, const Vec3& n_lookup, const SurfaceShading& s, const Vec3& wo, bool per_channel) {
    if (!per_channel) {
        const Vec3 D = in.light_dir[0] * 0.2126f + in.light_dir[1] * 0.7152f + in.light_dir[2] * 0.0722f;
        return one_pair(in.irradiance, D, n_lookup, s, wo);
    }
    IndirectLobes out;
    for (int c = 0; c < 3; ++c) {
        Color E(0);
        E[c] = in.irradiance[c];
        const IndirectLobes one = one_pair(E, in.light_dir[static_cast<size_t>(c)], n_lookup, s, wo);
        out.diffuse[c] = one.diffuse[c], out.specular[c] = one.specular[c];
    }
    return out;
}

Color indirect_radiance(const Indirect& in, const Vec3& n_lookup, const SurfaceShading& s, const Vec3& wo, bool per_channel) {
    const IndirectLobes l = indirect_lobes(in, n_lookup, s, wo, per_channel);
    return l.diffuse + l.specular;
}

}  // namespace bounce
