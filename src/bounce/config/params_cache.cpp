// The irradiance cache's rows of the parameter table (params.h).
#include "bounce/config/param_rows.h"

namespace bounce::param_rows {

namespace {

using R = RenderSettings;
constexpr unsigned cache = kCacheIdentity;

/// Where records go and how far each reaches.
void add_placement_rows(std::vector<Row>& rows) {
    rows.push_back(row("metric", "cache", &R::cache, &CacheSettings::metric)
                       .choices({"tl04", "ward", "hessian"})
                       .doc("record error metric: tl04 (normalised, bounded), ward (1/x, accuracy a) or hessian "
                            "(elliptical records sized by the gather's irradiance Hessian)")
                       .id(cache)
                       .flag());
    rows.push_back(row("min_spacing", "cache", &R::cache, &CacheSettings::min_spacing)
                       .range(0.1, 4096)
                       .unit("pixels")
                       .doc("smallest record radius")
                       .id(cache)
                       .flag());
    rows.push_back(row("max_spacing", "cache", &R::cache, &CacheSettings::max_spacing)
                       .range(0.1, 4096)
                       .unit("pixels")
                       .doc("largest record radius")
                       .id(cache)
                       .flag());
    rows.push_back(row("max_angle", "cache", &R::cache, &CacheSettings::max_angle)
                       .range(0.1, 90)
                       .unit("degrees")
                       .doc("normal deviation at which the normal metric reaches 1")
                       .id(cache)
                       .flag());
    rows.push_back(row("gradient_limit", "cache", &R::cache, &CacheSettings::gradient_limit)
                       .range(0, 1e6)
                       .doc("Weber limit tau: gradient-extrapolated change / E at which the metric reaches 1; 0 = off")
                       .id(cache)
                       .flag());
    rows.push_back(row("quality", "cache", &R::cache, &CacheSettings::quality)
                       .range(0.01, 100)
                       .doc("kappa: every TL04 metric is scaled by it; smaller = fewer records")
                       .id(cache)
                       .flag());
    rows.push_back(row("min_weight", "cache", &R::cache, &CacheSettings::min_weight)
                       .range(1e-6, 100)
                       .doc("a lookup misses when the weights sum below this (TL04)")
                       .id(cache)
                       .flag());
    rows.push_back(row("accuracy", "cache", &R::cache, &CacheSettings::accuracy).range(1e-3, 10).doc("Ward's a").id(cache).flag());
    rows.push_back(
        row("gradients", "cache", &R::cache, &CacheSettings::gradients).doc("extrapolate records with their gradients").id(cache).flag());
    rows.push_back(row("neighbour_clamp", "cache", &R::cache, &CacheSettings::neighbour_clamp)
                       .doc("R_new <= R_j + |p_new - p_j| (Krivanek et al. 2006)")
                       .id(cache)
                       .flag());
    rows.push_back(row("light_parts", "cache", &R::cache, &CacheSettings::light_parts)
                       .doc("records keep their bounce light per light and are placed as if every light were white at "
                            "intensity 1, so a light's colour or intensity edit rescales it exactly (the lighting tool's default)")
                       .id(cache));
    rows.push_back(row("radius_scale", "cache", &R::cache, &CacheSettings::radius_scale)
                       .range(0.01, 100)
                       .doc("R = radius_scale x d_min (TL04: 1/2)")
                       .id(cache)
                       .flag());
    rows.push_back(row("hessian_error", "cache", &R::cache, &CacheSettings::hessian_error)
                       .range(1e-5, 10)
                       .doc("hessian metric: relative second-order error at a record's edge; radii sqrt(2 e / |lambda|)")
                       .id(cache)
                       .flag());
    rows.push_back(row("max_anisotropy", "cache", &R::cache, &CacheSettings::max_anisotropy)
                       .range(1, 100)
                       .doc("hessian metric: the long radius is at most this many times the short one")
                       .id(cache)
                       .flag());
}

/// How records gather and are refined between.
void add_refinement_rows(std::vector<Row>& rows) {
    rows.push_back(row("min_rays", "cache", &R::cache, &CacheSettings::min_rays)
                       .range(0, 1 << 20)
                       .unit("rays")
                       .doc("adaptive records: a record first gathers this many rays and gathers render.rays only when "
                            "that estimate is noisier than ray_noise; 0 = every record gathers render.rays")
                       .id(cache)
                       .flag());
    rows.push_back(row("ray_noise", "cache", &R::cache, &CacheSettings::ray_noise)
                       .range(1e-4, 10)
                       .doc("relative standard error (estimated from the gather's strata) at which a record's first "
                            "gather is kept")
                       .id(cache)
                       .flag());
    rows.push_back(row("refine", "cache", &R::cache, &CacheSettings::refine)
                       .range(0, 100)
                       .doc("per-fragment refinement: a fragment whose covering records' extrapolated values spread "
                            "(weighted relative standard deviation) above this gets a gather of its own; 0 = off")
                       .flag());
    rows.push_back(row("refine_noise", "cache", &R::cache, &CacheSettings::refine_noise)
                       .range(0, 100)
                       .doc("per-fragment refinement: the records' spread counts only beyond what their own gathers' "
                            "noise explains (this many times their estimated variance): records that disagree only by "
                            "noise give a fragment nothing its own gather, as noisy, would improve; and beyond the "
                            "noise that own gather (at refine_rays) would add over the interpolation's, times the same "
                            "(docs/irradiance-cache.md); 0 = the raw spread")
                       .flag());
    rows.push_back(row("refine_band", "cache", &R::cache, &CacheSettings::refine_band)
                       .range(1, 100)
                       .doc("per-fragment refinement: a refined fragment's own gather replaces the interpolation wholly "
                            "only once the records' spread reaches this many times `refine`; below that the two are "
                            "blended in proportion, so a fragment crossing the threshold changes gradually (less "
                            "popping in a shot, docs/animation.md); 1 = a hard switch")
                       .flag());
    rows.push_back(row("refine_hold", "cache", &R::cache, &CacheSettings::refine_hold)
                       .range(0, 1)
                       .doc("per-fragment refinement in a shot: a fragment refined in the frame before (a still camera's "
                            "fragment on the same point) keeps its own gather until its records' spread falls below this "
                            "share of `refine` (hysteresis: no switching on and off as the spread hovers about the "
                            "threshold, docs/animation.md); 1 = none")
                       .flag());
    rows.push_back(row("refine_hold_reach", "cache", &R::cache, &CacheSettings::refine_hold_reach)
                       .range(0, 16)
                       .unit("pixels")
                       .doc("per-fragment refinement in a shot with a moving camera, whose fragments never land on the "
                            "points of the frame before: a fragment within this many pixel footprints, on its surface, of a "
                            "point refined in the frame before keeps `refine_hold` (docs/animation.md); 0 = the hold only "
                            "for a still camera")
                       .flag());
    rows.push_back(row("refine_rays", "cache", &R::cache, &CacheSettings::refine_rays)
                       .range(0, 1 << 20)
                       .unit("rays")
                       .doc("rays of a refined fragment's own gather; 0 = render.rays")
                       .flag());
}

/// The correction rays, displaced records, and how records live across the frames of a shot.
void add_record_life_rows(std::vector<Row>& rows) {
    rows.push_back(row("correction_rays", "cache", &R::cache, &CacheSettings::correction_rays)
                       .range(0, 1 << 16)
                       .unit("rays")
                       .doc("records as a control variate: every fragment gathers this many rays and adds to the records' "
                            "prediction (their direction bins, blended) the rays' measured difference from it: unbiased "
                            "whatever the records say, brute force at these rays where none covers it (docs/gather.md); "
                            "0 = interpolation alone")
                       .flag());
    rows.push_back(row("correction_prediction", "cache", &R::cache, &CacheSettings::correction_prediction)
                       .choices({"cells", "hits"})
                       .doc("records as a control variate: what they predict a fragment's correction rays see: `cells`, "
                            "each record's cells where it lies on the fragment's plane, else the records' direction bins; "
                            "`hits`, the records' cells' hit points seen from the fragment (parallax-correct; 24 bytes a ray "
                            "per record in memory, docs/gather.md)")
                       .flag());
    rows.push_back(row("displaced_records", "cache", &R::cache, &CacheSettings::displaced_records)
                       .choices({"undisplaced", "displaced"})
                       .doc("where records of displaced surfaces live: on the un-displaced surface (rays still leave the "
                            "displaced one) or on the displaced one")
                       .id(cache)
                       .flag());
    rows.push_back(row("displacement_near", "cache", &R::cache, &CacheSettings::displacement_near)
                       .range(0, 1e6)
                       .unit("displacement bounds")
                       .doc("records on the un-displaced surface: gather hits nearer than this many displacement bounds (the "
                            "surface's own bumps) neither shrink a record's radius nor steepen its gradients; 0 = off")
                       .id(cache)
                       .flag());
    rows.push_back(row("refine_tilt", "cache", &R::cache, &CacheSettings::refine_tilt)
                       .range(0, 180)
                       .unit("degrees")
                       .doc("records on the un-displaced surface: a fragment whose displaced normal tilts from the "
                            "un-displaced one by more than this gets a gather of its own (refine_rays); 0 = off")
                       .flag());
    rows.push_back(row("temporal_tolerance", "cache", &R::cache, &CacheSettings::temporal_tolerance)
                       .range(0, 100)
                       .doc("frames of a shot: a record kept from an earlier frame is gathered again (or re-shaded) once what "
                            "changed in its view may have moved its irradiance by more than this fraction of it; 0 = only "
                            "when nothing it sees changed")
                       .flag());
    rows.push_back(row("temporal_refine_reuse", "cache", &R::cache, &CacheSettings::temporal_refine_reuse)
                       .range(0, 4)
                       .unit("pixels")
                       .doc("frames of a shot: a fragment that refinement gathers for reuses the rays of the nearest "
                            "earlier frame's refinement gather within this many pixel footprints of it on its surface, "
                            "tracing again only its near rays (docs/animation.md); 0 = off")
                       .flag());
    rows.push_back(row("temporal_filter", "cache", &R::cache, &CacheSettings::temporal_filter)
                       .range(0, 0.99)
                       .doc("frames of a shot: a record gathered again keeps this share of its previous value (an "
                            "exponential filter along its anchor: less flicker, some lag); 0 = off")
                       .flag());
    rows.push_back(row("record_filter", "cache", &R::cache, &CacheSettings::record_filter)
                       .range(0, 100)
                       .unit("noise widths")
                       .doc("records filtered in record space before the shading pass interpolates them: each record's "
                            "irradiance (AO) becomes the mean of its neighbours' values extrapolated to it with their "
                            "gradients, weighed as interpolation weighs them and by how far each differs from its own "
                            "in this many widths of the two records' estimated noise, so differences noise explains "
                            "are averaged and edges are kept (docs/irradiance-cache.md); 0 = off")
                       .flag());
    rows.push_back(row("shading_reach", "cache", &R::cache, &CacheSettings::shading_reach)
                       .range(1, 10)
                       .doc("the shading pass lets records reach this much farther (kappa / reach)")
                       .flag());
}

}  // namespace

void add_cache_rows(std::vector<Row>& rows) {
    add_placement_rows(rows);
    add_refinement_rows(rows);
    add_record_life_rows(rows);
}

}  // namespace bounce::param_rows
