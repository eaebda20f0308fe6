// Irradiance cache records and the settings that govern where they are made and how far they
// reach. Formulas: docs/irradiance-cache.md.
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include "bounce/core/math.h"

namespace bounce {

struct CacheSettings {
    std::string metric = "tl04";  ///< tl04 (normalised, bounded) | ward (1/x, accuracy a)
    float min_spacing = 2.0f;     ///< smallest record radius, pixels
    float max_spacing = 16.0f;    ///< largest record radius, pixels
    float max_angle = 10.0f;      ///< normal deviation at which the normal metric reaches 1, degrees
    float gradient_limit = 1.0f;  ///< Weber limit tau: extrapolated change / E at which it reaches 1; 0 = off
    float quality = 1.0f;         ///< kappa: every TL04 metric is scaled by it (smaller = fewer records)
    float min_weight = 0.5f;      ///< a lookup misses when the weights sum below this (TL04)
    float accuracy = 0.2f;        ///< Ward's a
    bool gradients = true;        ///< extrapolate with gradients
    bool neighbour_clamp = true;  ///< R_new <= R_j + |p_new - p_j| (Krivanek et al. 2006)
    float shading_reach = 1.0f;   ///< the shading pass lets records reach this much farther
                                  ///< (kappa / reach; Mitsuba's relaxed final pass), >= 1
    float radius_scale = 0.5f;    ///< R = radius_scale * d_min (TL04: 1/2)
    /// The settings the shading pass interpolates with.
    CacheSettings for_shading() const {
        CacheSettings s = *this;
        s.quality = quality / shading_reach;
        s.accuracy = accuracy * shading_reach;
        return s;
    }
};

/// One cache record: a full gather's result at (p, n), with its reach.
struct Record {
    Vec3 p, n;                   ///< where it was gathered (un-displaced, un-bumped)
    Color E{0};                  ///< irradiance
    float ao = 1;
    Vec3 bent{0, 0, 1};          ///< bent normal (unit)
    std::array<Vec3, 3> dir{};   ///< per-channel light directions (unnormalised, see gather.h)
    std::array<Vec3, 3> grad_r{}, grad_t{};  ///< irradiance gradients per channel
    Vec3 ao_grad_r{0}, ao_grad_t{0};
    float radius = 0;            ///< validity radius R_i (world), after all clamps
    float raw_radius = 0;        ///< radius before the screen-space clamps (neighbour clamping)
    float footprint = 0;         ///< world width of a pixel at p
    float harmonic = 0, dmin = 0;  ///< gather distances (harmonic mean, qualifying minimum)
    float weber = INFINITY;      ///< distance at which the gradient change reaches tau E (world)
    float support = 0;           ///< weights are zero beyond this distance (octree placement)
    uint64_t key = 0;            ///< creation key (pixel, fragment): deterministic order
    uint32_t rays = 0;
    int32_t frame = 0;           ///< frame it was gathered in (sequences: reused vs new)
};

/// Normalised error terms of record `r` at (p, n); each reaches 1 exactly at its bound.
struct MetricTerms {
    float position = 0;  ///< |p - p_i| / R_i
    float normal = 0;    ///< sqrt(1 - n.n_i) / sqrt(1 - cos(max_angle))
    float gradient = 0;  ///< |grad| |p - p_i| / (tau E_i), floored so records reach R_min
    bool behind = false; ///< p is in front of the record (sees what it did not) or faces away
};

MetricTerms metric_terms(const Record& r, const Vec3& p, const Vec3& n, const CacheSettings& s);

/// The record's weight at (p, n): TL04 1 - kappa max(terms) (0 when rejected), or Ward's
/// 1 / (|dp|/R + sqrt(1 - n.n_i)) (0 below 1/a).
float record_weight(const Record& r, const Vec3& p, const Vec3& n, const CacheSettings& s);

/// Distance beyond which `record_weight` is 0 for any normal.
float record_support(const Record& r, const CacheSettings& s);

}  // namespace bounce
