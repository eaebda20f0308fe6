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

MetricTerms metric_terms(const Record& r, const Vec3& p, const Vec3& n, const RecordMetric& s) {
    MetricTerms m;
    Vec3 d = p - r.p;
    float dist = length(d);
    float ndot = dot(n, r.n);
    // Behind test (Ward, tolerance relative to the radius): p lies in front of the record's
    // tangent plane by more than 5% of R and so sees geometry the record did not.
    m.behind = ndot <= 0 || dot(d, n + r.n) * 0.5f < -0.05f * r.radius;
    if (r.radius_long > r.radius) {  // an ellipse: the long radius along the axis
        const float along = dot(d, r.axis);
        m.position = std::sqrt(std::max(0.0f, dist * dist - along * along) / (r.radius * r.radius) +
                               along * along / (r.radius_long * r.radius_long));
    } else {
        m.position = dist / r.radius;
    }
    m.normal = std::sqrt(std::max(0.0f, 1 - ndot)) / s.normal_bound;
    m.gradient = std::isfinite(r.weber) ? dist / r.weber : 0.0f;
    return m;
}

float record_weight(const Record& r, const Vec3& p, const Vec3& n, const RecordMetric& s) {
    if (s.metric == Metric::Ward) {
        float ndot = dot(n, r.n);
        Vec3 d = p - r.p;
        if (ndot <= 0 || dot(d, n + r.n) * 0.5f < -0.05f * r.radius) return 0;
        float e = length(d) / r.radius + std::sqrt(std::max(0.0f, 1 - ndot));
        float w = e > 1e-3f ? 1 / e : 1e3f;  // Radiance's cap
        return w > 1 / s.accuracy ? w : 0;
    }
    MetricTerms m = metric_terms(r, p, n, s);
    if (m.behind) return 0;
    float e = s.quality * std::max({m.position, m.normal, m.gradient});
    return e < 1 ? 1 - e : 0;
}

float record_support(const Record& r, const CacheSettings& s) {
    if (s.metric == Metric::Ward) return s.accuracy * r.radius;
    return std::min(std::max(r.radius, r.radius_long), r.weber) / s.quality;
}

}  // namespace bounce
