// Irradiance cache records and the settings that govern where they are made and how far they
// reach. Formulas: docs/irradiance-cache.md.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "bounce/core/math.h"
#include "bounce/gather/gather.h"
#include "bounce/config/settings.h"

namespace bounce {

inline constexpr uint32_t kNoAnchor = 0xffffffffu;

/// One cache record: a full gather's result at (p, n), with its reach.
struct Record {
    Vec3 p, n;   ///< where it was gathered (un-displaced, un-bumped)
    Color E{0};  ///< irradiance
    float ao = 1;
    Vec3 bent{0, 0, 1};                      ///< bent normal (unit)
    std::array<Vec3, 3> dir{};               ///< per-channel light directions (unnormalised, see gather.h)
    std::array<Vec3, 3> grad_r{}, grad_t{};  ///< irradiance gradients per channel
    Vec3 ao_grad_r{0}, ao_grad_t{0};
    float radius = 0;              ///< validity radius R_i (world), after all clamps; hessian: the short one
    float radius_long = 0;         ///< hessian: the radius along `axis` (>= radius); 0 = round
    Vec3 axis{0};                  ///< hessian: unit tangent direction of the long radius
    float raw_radius = 0;          ///< radius before the screen-space clamps (neighbour clamping)
    float footprint = 0;           ///< world width of a pixel at p
    float harmonic = 0, dmin = 0;  ///< gather distances (harmonic mean, qualifying minimum)
    float weber = INFINITY;        ///< distance at which the gradient change reaches tau E (world)
    float support = 0;             ///< weights are zero beyond this distance (octree placement)
    uint64_t key = 0;              ///< creation key (pixel, fragment): deterministic order and its random stream
    uint32_t rays = 0;
    float noise = 0;    ///< its gather's relative standard error (GatherResult::rel_stderr)
    int32_t frame = 0;  ///< frame it was created in (sequences: reused vs new)
    // Frames of a shot (temporal.h).
    Vec3 origin{0};                         ///< where the gather's rays left from (world)
    std::array<float, kReachBins> reach{};  ///< farthest hit per direction bin (INFINITY: a ray escaped)
    /// Mean radiance per direction bin (GatherResult::bins; unoccluded fraction in AO mode): the
    /// record's prediction for a fragment's correction rays (control_variate.h). Null when every
    /// bin is 0 (without render.correction_rays): 384 bytes inline cost every record of a shot
    /// that much whether it predicted anything or not.
    std::shared_ptr<const std::array<Color, kReachBins>> bins;
    /// Its bins, 0 where it keeps none.
    const std::array<Color, kReachBins>& bin_values() const {
        static const std::array<Color, kReachBins> zero{};
        return bins ? *bins : zero;
    }
    /// Keeps `values` unless every one is 0.
    void set_bins(const std::array<Color, kReachBins>& values) {
        const bool any = std::any_of(values.begin(), values.end(), [](const Color& c) { return c.x != 0 || c.y != 0 || c.z != 0; });
        bins = any ? std::make_shared<const std::array<Color, kReachBins>>(values) : nullptr;
    }
    /// Its gather's every cell (GatherResult::cells; not in files): the prediction for fragments
    /// on its own plane.
    std::shared_ptr<const std::vector<Color>> cells;
    /// With correction_prediction "hits": its cells' hit points (GatherResult::cell_hits; not in files).
    std::shared_ptr<const std::vector<Vec3>> cell_hits;
    GatherGrid grid;
    uint32_t anchor = kNoAnchor;  ///< the moving object whose surface carries it, or kNoAnchor (static)
    /// Rigid objects: p and n in the object's own space (before its placement). Deforming
    /// objects: the triangle of its visible mesh (anchor_prim) and p's barycentrics (anchor_p.x, .y).
    Vec3 anchor_p{0}, anchor_n{0};
    uint32_t anchor_prim = kNoAnchor;
    int32_t gathered = 0;                     ///< frame of its last gather or re-shade
    float near = 0;                           ///< its gather's `near` (Gatherer::gather), to gather it again alike
    float drift = 0;                          ///< bound on how far its irradiance may have moved since (relative to E)
    std::shared_ptr<const GatherHits> hits;   ///< kept only when a shot may re-shade it (not in files)
    std::shared_ptr<const LightParts> parts;  ///< CacheSettings::light_parts only (in files from version 5)
    /// render.guided only (not in files): how its gather's cells varied per direction bin, the
    /// guide of the refinement gathers of fragments it covers (guide.h).
    std::shared_ptr<const DirectionGuide> guide;
};

/// A record's irradiance and AO as the shading pass reads them when records are filtered in
/// record space (CacheSettings::record_filter, record_filter.h).
struct FilteredValue {
    Color E{0};
    float ao = 1;
};

/// Sets r's irradiance, directions and gradients from its light parts at `scales` (no parts: as it is).
void apply_light_scales(Record& r, std::span<const Color> scales);

/// A record's value E extrapolated by its gradients over dp (translation) and rot (n_i x n),
/// clamped to [0, 4 E] per channel.
Color extrapolated(const Color& E, const std::array<Vec3, 3>& grad_t, const std::array<Vec3, 3>& grad_r, const Vec3& dp, const Vec3& rot);

/// A record's AO extrapolated the same way, clamped to [0, 1].
float extrapolated_ao(float ao, const Vec3& grad_t, const Vec3& grad_r, const Vec3& dp, const Vec3& rot);

/// Normalised error terms of record `r` at (p, n); each reaches 1 exactly at its bound.
struct MetricTerms {
    float position = 0;   ///< |p - p_i| / R_i
    float normal = 0;     ///< sqrt(1 - n.n_i) / sqrt(1 - cos(max_angle))
    float gradient = 0;   ///< |grad| |p - p_i| / (tau E_i), floored so records reach R_min
    bool behind = false;  ///< p is in front of the record (sees what it did not) or faces away
};

/// What a record's weight reads of a cache's settings, with the normal term's bound worked out
/// once (a cache keeps one per weighting: the gathering pass's and the shading pass's).
struct RecordMetric {
    Metric metric = Metric::TL04;
    float quality = 1, accuracy = 0;
    float normal_bound = 0;  ///< sqrt(1 - cos(max_angle))
    explicit RecordMetric(const CacheSettings& s);
};

/// What a record's weight reads of it, packed apart from the record (a cache keeps one per
/// record beside them): a lookup weighs every candidate the octree gives it, and reading these
/// 48 bytes instead of a Record's scattered fields (three cache lines of ~900 bytes) was most
/// of a lookup's time (issue 64).
struct RecordShape {
    Vec3 p;
    float radius = 0;
    Vec3 n;
    float radius_long = 0;
    Vec3 axis;
    float weber = INFINITY;
    explicit RecordShape(const Record& r) : p(r.p), radius(r.radius), n(r.n), radius_long(r.radius_long), axis(r.axis), weber(r.weber) {}
};

/// Inline: every lookup calls it once per candidate record.
inline MetricTerms metric_terms(const RecordShape& r, const Vec3& p, const Vec3& n, const RecordMetric& s) {
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

inline MetricTerms metric_terms(const Record& r, const Vec3& p, const Vec3& n, const RecordMetric& m) {
    return metric_terms(RecordShape(r), p, n, m);
}

/// The record's weight at (p, n): TL04 1 - kappa max(terms) (0 when rejected), or Ward's
/// 1 / (|dp|/R + sqrt(1 - n.n_i)) (0 below 1/a).
inline float record_weight(const RecordShape& r, const Vec3& p, const Vec3& n, const RecordMetric& s) {
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

inline float record_weight(const Record& r, const Vec3& p, const Vec3& n, const RecordMetric& m) {
    return record_weight(RecordShape(r), p, n, m);
}

/// Distance beyond which `record_weight` is 0 for any normal.
float record_support(const Record& r, const CacheSettings& s);

}  // namespace bounce
