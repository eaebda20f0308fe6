// The hemisphere gather: the one expensive operation that brute force runs at every fragment
// and the irradiance cache runs only at its records. Cosine-stratified M x N grid (N ~ pi M),
// one bounce: each hit is shaded with the direct light leaving it (radiosity textures or
// shadow rays), escaped rays see the sky.
#pragma once

#include <array>
#include <memory>
#include <span>
#include <vector>

#include "bounce/accel/accel.h"
#include "bounce/core/random.h"
#include "bounce/core/progress.h"
#include "bounce/core/stats.h"
#include "bounce/deep/deep_buffer.h"
#include "bounce/gather/grid.h"
#include "bounce/gather/light_parts.h"
#include "bounce/lighting/lighting.h"
#include "bounce/radiosity/radiosity.h"

namespace bounce {

/// The gather parameters (config/settings.h) as plan_frame resolves them (`ao_distance` <= 0 =
/// unlimited), plus what the caller decides per pass.
struct GatherSettings : IndirectSettings {
    FrameTiling tiling;                   ///< the frame's seed (every gather's stream) and tiles
    bool record_terms = true;             ///< distances and gradients (what a cache record needs); brute
                                          ///< force turns them off and gathers only E, AO and directions
    const CancelToken* cancel = nullptr;  ///< checked once per gather
    bool hessian = false;                 ///< also the irradiance Hessian (record_terms only)
    /// Also the bounce light per light (GatherResult::parts; not in AO mode). Then
    /// every value of the result is its `signal` (every light at scale 1): what decides where
    /// records go and how many rays they take depends on no light's colour or intensity.
    bool light_parts = false;
    /// With record_terms: also what a record predicts for a fragment's correction rays
    /// (GatherResult::bins and cells; CacheSettings::correction_rays). Off, records carry
    /// neither: a 512-ray record's cells alone are 6 KB.
    bool prediction = false;
    /// With prediction: also each cell's hit point (GatherResult::cell_hits;
    /// CacheSettings::correction_prediction "hits").
    bool prediction_hits = false;
};

struct DirectionGuide;
namespace detail {
struct Cells;
}

/// Where GatherResult::cell_hits puts an escaped ray's hit: this far along its direction (seen
/// from any point of a scene, still that direction).
inline constexpr float kEscapedHit = 1e20f;

/// What a gather returns; gradients follow Ward-Heckbert (rotational) and Ward-Heckbert with
/// Krivanek's occlusion-aware distances (translational), see docs/gather.md.
struct GatherResult {
    Color irradiance{0};                 ///< E, one bounce plus the sky
    float ao = 1;                        ///< cosine-weighted unoccluded fraction
    Vec3 bent_normal{0, 0, 1};           ///< mean unoccluded direction (unit)
    std::array<Vec3, 3> light_dir{};     ///< per channel c: (pi/S) sum L_c w (not normalised)
    float harmonic_distance = INFINITY;  ///< Ward's R: S / sum(1/r)
    float min_distance = INFINITY;       ///< TL04's: min r over qualifying rays
    std::array<Vec3, 3> grad_rot{};      ///< dE_c/d(rotation): E(n') ~ E + (n x n') . grad
    std::array<Vec3, 3> grad_trans{};    ///< dE_c/dx
    Vec3 ao_grad_rot{0}, ao_grad_trans{0};
    int rays = 0;
    /// With record_terms: estimated relative standard error of the irradiance's luminance (AO in AO mode), from
    /// the differences of azimuthally adjacent cells: each pair's squared difference estimates
    /// the two strata's variance, Var(E) ~ (pi/S)^2 sum_pairs d^2.
    float rel_stderr = 0;
    /// With GatherSettings::hessian: the tangent Hessian of relative irradiance (hessian.h).
    Vec3 hess_axis{0};
    float hess_slow = 0, hess_fast = 0;
    /// With record_terms: the farthest hit per direction bin (INFINITY where a ray escaped).
    std::array<float, kReachBins> reach{};
    /// With prediction: the mean radiance per direction bin (direction_bin; the unoccluded
    /// fraction, grey, in AO mode; a bin no ray fell in takes the mean over all): what a record
    /// predicts a nearby fragment's rays will see (cache/control_variate.h).
    std::array<Color, kReachBins> bins{};
    /// With prediction: every cell's radiance (unoccluded fraction in AO mode), cell j * n + k
    /// of the gather's grid: a finer prediction for fragments on the record's own plane.
    std::shared_ptr<const std::vector<Color>> cells;
    /// With prediction_hits: every cell's hit point (an escaped ray's: kEscapedHit along its
    /// direction), so that a fragment can see the cells from its own point.
    std::shared_ptr<const std::vector<Vec3>> cell_hits;
    GatherGrid grid;
    std::shared_ptr<LightParts> parts;  ///< GatherSettings::light_parts: per light
    /// With record_terms and GatherSettings::guided: how its cells varied per direction bin,
    /// the guide of nearby guided gathers (refinement's; guide.h).
    std::shared_ptr<const DirectionGuide> guide;
};

/// Gathers at `p` (on the fine surface) over the hemisphere of unit normal `n`.
class Gatherer {
  public:
    /// `radiosity` may be null: hits are then shaded with shadow rays.
    Gatherer(const Scene& scene, const SceneAccel& accel, const Materials& materials, const DirectLighting& lighting,
             const RadiosityTextures* radiosity, GatherSettings settings);

    /// `near`: hits nearer than this neither limit the record radius (TL04's d_min) nor steepen
    /// the translational gradients (their cell distances are floored at it). Records on the
    /// un-displaced surface pass a few displacement bounds, so the displacement's own bumps do
    /// not shrink them (CacheSettings::displacement_near); the light they gather is unchanged.
    /// `hits`, if given, receives every ray's hit (for a later reshade).
    GatherResult gather(const Vec3& p, const Vec3& n, const RandomStream& rng, Counters& counters, float near = 0,
                        GatherHits* hits = nullptr) const;
    /// The same gather (same p, n, rng and settings) from the hits it traced: no ray is traced,
    /// every hit is shaded with today's light. Bit-identical to gather() when the scene's
    /// geometry is what it was and the hits are gather()'s.
    GatherResult reshade(const Vec3& p, const Vec3& n, const RandomStream& rng, const GatherHits& hits, Counters& counters,
                         float near = 0) const;
    /// The same gather again where only some rays may hit something else (a moving object's
    /// swept bounds): those cells (`cells`, from cells_through) are traced again and `hits`
    /// updated, the rest keep their hits, and every hit is shaded with today's light.
    GatherResult update(const Vec3& p, const Vec3& n, const RandomStream& rng, GatherHits& hits, std::span<const uint32_t> cells,
                        Counters& counters, float near = 0) const;
    /// A gather at (p, n) made mostly of an earlier one's rays (`from`, made nearby on the same
    /// surface with the same settings; reproject.cpp says how): what lies farther from from.p
    /// than kReprojectNear times the distance between the points (and the sky) is taken from its
    /// hits, seen from p; the cells whose rays met anything nearer, and a margin around them,
    /// are traced again from p with `rng` for what is near. `rays` in the result counts those.
    /// E, AO, bent normal and light directions only (no gradients, no light parts).
    GatherResult reproject(const Vec3& p, const Vec3& n, const RandomStream& rng, const EarlierGather& from, Counters& counters) const;
    static constexpr float kReprojectNear = 16;
    /// A plain gather that also reports, per direction bin of n's frame, how much its cells'
    /// values varied there: the guide of nearby guided gathers (guide.h).
    DirectionGuide pilot(const Vec3& p, const Vec3& n, const RandomStream& rng, Counters& counters) const;
    /// A gather of the same number of rays spread over the direction bins by `guide` (its
    /// share GatherSettings::guided; guide.h): E, AO, bent normal, light directions and the
    /// harmonic distance (no gradients). With light parts it is the plain gather.
    GatherResult gather_guided(const Vec3& p, const Vec3& n, const RandomStream& rng, const DirectionGuide& guide,
                               Counters& counters) const;
    const GatherSettings& settings() const { return settings_; }
    /// The same gatherer with `rays` rays per gather.
    Gatherer with_rays(int rays) const {
        GatherSettings s = settings_;
        s.rays = rays;
        return Gatherer(scene_, accel_, materials_, lighting_, radiosity_, s);
    }
    GatherGrid grid() const { return grid_; }

  private:
    /// This thread's scratch of the current gather: the cells' directions, hits and values, which
    /// every entry point fills and hands to the steps below (a pool per gatherer, one per thread).
    detail::Cells& scratch() const;
    /// The directions of the gather's cells (stratified, cosine-weighted) about n, into `cells`.
    void cell_directions(detail::Cells& cells, const Vec3& n, const RandomStream& rng) const;
    /// Everything a gather computes from its cells' directions and hits.
    GatherResult finish(detail::Cells& cells, const Vec3& p, const Vec3& n, const RandomStream& rng, Counters& counters, float near) const;
    /// The current gather's cells' spread per direction bin of n's frame (DirectionGuide).
    DirectionGuide cells_guide(const detail::Cells& cells, const Vec3& n) const;
    /// The radiance cell c of the current gather brings (its hit's or the sky's; 0 in AO mode),
    /// setting the cell's hit normal (Cells::NH) where a record's terms or AO need it.
    Color cell_radiance(detail::Cells& cells, const Vec3& p, size_t c, const RandomStream& rng, Counters& counters,
                        std::span<Color> parts) const;
    /// Radiance leaving a hit towards the gather point (direction -d). With `parts` (one per
    /// light): per light, scales factored out, and their sum is returned (the signal).
    Color hit_radiance(const Hit& h, const SurfacePoint& sp, const Vec3& d, const RandomStream& rng, uint64_t ray, Counters& counters,
                       std::span<Color> parts) const;
    /// The same from a strand of fur at `at` (fur.cast_indirect), and from the sky where a ray escapes.
    Color hair_radiance(const Hit& h, const Vec3& at, const Vec3& d, const RandomStream& rng, uint64_t ray, Counters& counters,
                        std::span<Color> parts) const;
    Color escaped_radiance(const Vec3& d, std::span<Color> parts) const;
    /// A hit at distance t's share of AO's unoccluded fraction (ao_distance, ao_falloff).
    float unoccluded(float t) const;
    /// The light-linear sums of the current gather over cell values L[c * stride]: E and light
    /// directions, and with `gradients` the rotational and translational gradients.
    LightPart light_part(const detail::Cells& cells, const Color* L, size_t stride, const Frame& frame, float near, bool gradients) const;

    const Scene& scene_;
    const SceneAccel& accel_;
    const Materials& materials_;
    const DirectLighting& lighting_;
    const RadiosityTextures* radiosity_;
    GatherSettings settings_;
    GatherGrid grid_;
    float cos_concave_;
    std::vector<uint32_t> packet_order_;  ///< grid cells in 4x4 blocks: coherent packets of 16
    float far_;                           ///< where a ray that leaves the scene is taken to end, for the Hessian's mesh
    size_t lights_;                       ///< GatherSettings::light_parts: the scene's lights (0: no parts)
    std::vector<Color> unit_scales_;      ///< every light at scale 1 (the signal)
    /// The cells reprojection traces again about each cell of the grid (made once per gatherer).
    const std::vector<std::vector<uint32_t>>& reprojection_margins() const;

    struct Scratch;
    std::shared_ptr<Scratch> scratch_;  ///< per thread (copies of a gatherer share it)
};

}  // namespace bounce

namespace bounce {

/// Indirect light at one fragment, as the shading pass consumes it (from a gather or, later,
/// interpolated from the irradiance cache).
struct Indirect {
    Color irradiance{0};
    float ao = 1;
    Vec3 bent_normal{0, 0, 1};
    std::array<Vec3, 3> light_dir{};  ///< per channel: mean incoming direction x radiance (GatherResult)
    /// A thin translucent surface's irradiance through its back hemisphere (about -n; its own
    /// records: docs/shading.md); 0 elsewhere.
    Color back{0};
};

/// Each scene light's share of every fragment's indirect light, per channel (render.light_parts:
/// from the records' light parts), for the per-light indirect layers.
struct LightShares {
    size_t lights = 0;
    std::vector<Color> share;  ///< share[fragment * lights + i], parallel to deep.fragments
    std::span<const Color> at(size_t fragment) const { return {share.data() + fragment * lights, lights}; }
    std::span<Color> at(size_t fragment) { return {share.data() + fragment * lights, lights}; }
};

/// Where a hair fragment's indirect light is gathered and looked up: its strand's root on the
/// growing surface, about that surface's normal there (fur.indirect_at "fragment": its own
/// point, about the same normal). Hair fragments have no normal of their own worth a hemisphere.
struct HairSite {
    Vec3 p, n;
};
HairSite hair_site(const Scene& scene, const Fragment& f);
/// Where a per-fragment gather (brute force, a pilot, a correction) is made: a hair fragment's
/// hair_site, any other fragment's own point and normal.
inline HairSite gather_site(const Scene& scene, const Fragment& f) { return f.is_hair() ? hair_site(scene, f) : HairSite{f.p, f.n}; }

/// Whether fragment f's image uses the bounce light at all: not a holdout's (matte), nor a
/// perfect mirror's or a clear glass's (base share 0 at every angle: it shows only what its
/// specular paths bring). The gathering, refinement and interpolation passes and brute force
/// skip the others (no records, no gathers; their indirect layers are 0 and their AO 1).
bool needs_bounce_light(const Scene& scene, const Fragment& f);
/// Whether fragment f also takes bounce light through its back hemisphere (Indirect::back): a
/// thin translucent surface's (Material::diffuse_transmission) in a render of light (AO looks
/// at one side: not with `ao`).
bool takes_back_light(const Scene& scene, const Fragment& f, bool ao);

/// A fragment that takes bounce light, as the per-fragment passes (brute force, the control
/// variate's correction) gather it: its index in deep.fragments, its window pixel, the site of
/// its hemisphere (hair: HairSite) and its random stream (fragment_stream).
struct BounceFragment {
    size_t index;
    int wx, wy;
    const Fragment& f;
    HairSite site;
    RandomStream rng;
};
/// fn(const BounceFragment&) for every fragment of `deep` that needs_bounce_light, tiles in
/// parallel under progress `name`.
template <class Fn>
void for_each_bounce_fragment(const Scene& scene, const DeepBuffer& deep, const FrameTiling& tiling, ProgressSink* sink, const char* name,
                              Fn&& fn) {
    for_each_pixel_in_tiles(deep, tiling.tile_size, sink, name, [&](int wx, int wy, size_t first) {
        auto frags = deep.pixel(wx, wy);
        for (uint32_t k = 0; k < frags.size(); ++k) {
            const Fragment& f = frags[k];
            if (!needs_bounce_light(scene, f)) continue;
            fn(BounceFragment{first + k, wx, wy, f, gather_site(scene, f), fragment_stream(tiling.seed, wx + deep.x0, wy + deep.y0, k)});
        }
    });
}

/// Brute force: gathers at every fragment of `deep` (tiles in parallel; guided by pilot gathers
/// with GatherSettings::guided, guide.h); the result is parallel to deep.fragments and
/// independent of thread count.
std::vector<Indirect> gather_every_fragment(const Scene& scene, const DeepBuffer& deep, const Gatherer& gatherer, Stats& stats,
                                            ProgressSink* progress);

}  // namespace bounce
