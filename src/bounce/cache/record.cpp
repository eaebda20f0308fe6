#include "bounce/cache/record.h"

namespace bounce {

MetricTerms metric_terms(const Record& r, const Vec3& p, const Vec3& n, const CacheSettings& s) {
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
    float cos_max = std::cos(s.max_angle * kPi / 180.0f);
    m.normal = std::sqrt(std::max(0.0f, 1 - ndot)) / std::sqrt(1 - cos_max);
    m.gradient = std::isfinite(r.weber) ? dist / r.weber : 0.0f;
    return m;
}

float record_weight(const Record& r, const Vec3& p, const Vec3& n, const CacheSettings& s) {
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
