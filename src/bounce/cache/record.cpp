#include "bounce/cache/record.h"

#include <algorithm>
#include <cmath>

namespace bounce {

RecordMetric::RecordMetric(const CacheSettings& s)
    : metric(s.metric), quality(s.quality), accuracy(s.accuracy), normal_bound(std::sqrt(1 - std::cos(s.max_angle * kPi / 180.0f))) {}

void apply_light_scales(Record& r, std::span<const Color> scales) {
    if (!r.parts) return;
    const LightPart v = combine_parts(*r.parts, scales);
    r.E = v.E, r.dir = v.dir, r.grad_r = v.grad_r, r.grad_t = v.grad_t;
}

Color extrapolated(const Color& E, const std::array<Vec3, 3>& grad_t, const std::array<Vec3, 3>& grad_r, const Vec3& dp, const Vec3& rot) {
    Color e = E;
    for (int c = 0; c < 3; ++c) {
        auto k = static_cast<size_t>(c);
        float v = E[c] + dot(dp, grad_t[k]) + dot(rot, grad_r[k]);
        e[c] = std::clamp(v, 0.0f, 4 * E[c]);  // extrapolation clamp [0, 4 E_i]
    }
    return e;
}

float extrapolated_ao(float ao, const Vec3& grad_t, const Vec3& grad_r, const Vec3& dp, const Vec3& rot) {
    return std::clamp(ao + dot(dp, grad_t) + dot(rot, grad_r), 0.0f, 1.0f);
}

float record_support(const Record& r, const CacheSettings& s) {
    if (s.metric == Metric::Ward) return s.accuracy * r.radius;
    return std::min(std::max(r.radius, r.radius_long), r.weber) / s.quality;
}

}  // namespace bounce
