// The settings of every pipeline stage, as plain data. Each struct belongs to one stage and its
// defaults are written here and nowhere else; the parameter table (params.h) names each field
// once and derives from it the JSON keys, CLI flags, identities, metadata and the docs table.
// They live in a room of their own (config/), below the world (scene/): the scene file carries
// them, but a stage receives its own struct from the frame's plan (render/frame_plan.h) and
// never reads another's.
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include "bounce/core/tiles.h"

namespace bounce {

enum class GiMode : uint8_t { None, Brute, Cache };
enum class Metric : uint8_t { TL04, Ward, Hessian };
enum class CacheSharing : uint8_t { Shared, PerThread };
enum class RecordSurface : uint8_t { Undisplaced, Displaced };
/// What records predict for the control variate (docs/gather.md): their cells on a fragment's
/// own plane, else their direction bins; or their cells' hit points seen from the fragment.
enum class CorrectionPrediction : uint8_t { Cells, Hits };
/// Which layers the EXR holds beside the standard ones (shade/layers.h).
enum class LayerSet : uint8_t { Standard, Components };
/// The bounce light at the surfaces mirrors and glass show: from the cache (records the
/// gathering pass makes for them; brute force gathers there), or from the radiosity textures.
enum class SpecularHitLight : uint8_t { Cache, Radiosity };
/// Where a gather hit on a small instance (a placement none of whose triangles reaches a
/// radiosity texel) takes its direct light: whichever costs less by a probe of the frame's
/// gathers (Auto), shadow rays at the hit, or the placement's lattice.
enum class SmallInstanceLight : uint8_t { Auto, Hit, Lattice };

/// Primary visibility and the deep file.
struct VisibilitySettings {
    int spp = 16;                         ///< jittered subsamples per pixel
    uint64_t seed = 0;                    ///< every random number is a hash of (pixel, sample, dimension, seed)
    std::array<int, 4> crop{0, 0, 0, 0};  ///< x0,x1,y0,y1 (exclusive ends); all 0 = full frame
    bool has_crop() const { return crop[1] > crop[0] || crop[3] > crop[2]; }
};

/// Dicing subdivision surfaces into the two tessellations (dice/subdivision.h).
struct DicingSettings {
    float shading_rate = 1;    ///< pixels per micropolygon edge on the fine tessellation
    int ray_level = 2;         ///< subdivision level of the coarse tessellation secondary rays trace
    int max_level = 5;         ///< cap on the fine tessellation's level (memory: x4 per level)
    float memory_budget = 16;  ///< GiB generated geometry (fur) may take; more is refused up front
};

/// Direct lighting and ray tracing.
struct LightingSettings {
    int light_samples = 16;  ///< stratified samples per area light / sky per fragment
    float ray_offset = -1;   ///< ray-origin offsetting distance; < 0 = automatic
    /// A point linked to more point, spot and quad lights than this samples this many of them,
    /// by their unshadowed contribution (unbiased); 0 = every light at every point.
    int light_pick = 64;
};

/// Radiosity textures: direct light baked on every triangle for the gather's hits.
struct RadiositySettings {
    bool enabled = true;    ///< shade gather hits from baked textures
    std::string folder;     ///< reuse/save them here; empty = bake in memory
    float texel = 0;        ///< lattice spacing, world units; 0 = diagonal / 128
    int light_samples = 0;  ///< light samples per lattice point; 0 = LightingSettings's
    /// Cap on the per-triangle lattice level (not a parameter): the level's byte. The auto
    /// texel (the scene size / 128) never reaches it; it was 32, which left a large triangle's
    /// lattice up to 4x coarser than the texel and blurred its shadows into every gather that
    /// saw it (issue 64: 2.7 -> 1.6 % from Cycles' answer on the Cornell box, 8.9 -> 3.6 % on
    /// the bunny's ground).
    int max_level = 255;
    /// A far forest's sides are hit by a few gather rays each, fewer than a level-1 lattice's
    /// 3 points x light samples: lit at the hit, one light sample per light, they are never
    /// baked; an orchard's near trees are hit tens of times per side and keep their lattice
    /// (issue 64, docs/gather.md).
    SmallInstanceLight small_instances = SmallInstanceLight::Auto;
    /// Not a parameter: the plan's count of the frame's gather rays if every pixel gathered
    /// once (pixels x rays), against which Auto weighs a probe's hits (0: no gathers).
    double pixel_gather_rays = 0;
    /// Every lattice point keeps its light per light, each light's scale factored out (not a
    /// parameter: the plan sets it from CacheSettings::light_parts).
    bool light_parts = false;
};

/// The hemisphere gather and which indirect light the render computes.
struct IndirectSettings {
    GiMode gi = GiMode::None;
    bool ao = false;         ///< ambient occlusion only
    int rays = 512;          ///< rays per gather
    float ao_distance = -1;  ///< < 0 = 10 % of the scene diagonal; 0 = unlimited
    float ao_falloff = 0;
    int hit_light_samples = 1;  ///< shadow samples at gather hits without radiosity textures
    float concave_angle = 80;   ///< degrees (TL04 distance filter)
    float guided = 0;           ///< share of a per-fragment gather's rays placed by a guide (gather/guide.h); 0 = off
    bool any() const { return gi != GiMode::None || ao; }
};

/// Where the irradiance cache makes records and how far they reach (docs/irradiance-cache.md).
struct CacheSettings {
    Metric metric = Metric::TL04;  ///< tl04 (normalised, bounded) | ward (1/x, accuracy a) | hessian (two radii)
    float min_spacing = 2.0f;      ///< smallest record radius, pixels
    float max_spacing = 16.0f;     ///< largest record radius, pixels
    float max_angle = 10.0f;       ///< normal deviation at which the normal metric reaches 1, degrees
    float gradient_limit = 0.1f;   ///< Weber limit tau; 0 = off (0.1: issue 15, docs/irradiance-cache.md)
    float quality = 1.0f;          ///< kappa: every TL04 metric is scaled by it
    float min_weight = 1.5f;       ///< a lookup misses below this weight sum (TL04; 1.5: issue 15, docs/irradiance-cache.md)
    float accuracy = 0.2f;         ///< Ward's a
    bool gradients = true;         ///< extrapolate with gradients
    bool neighbour_clamp = true;   ///< R_new <= R_j + |p_new - p_j| (Krivanek et al. 2006)
    float shading_reach = 1.0f;    ///< the shading pass lets records reach this much farther (>= 1)
    float radius_scale = 0.5f;     ///< R = radius_scale * d_min (TL04: 1/2)
    float hessian_error = 0.05f;   ///< hessian: relative second-order error allowed at a record's edge
    float max_anisotropy = 4;      ///< hessian: long radius / short radius at most
    int min_rays = 0;              ///< a record's first gather; more (render.rays) only if noisier than ray_noise; 0 = off
    float ray_noise = 0.02f;       ///< relative standard error a record's first gather must reach to stop there
    float refine = 0.1f;           ///< a fragment whose records disagree by more than this gets its own gather; 0 = off
    float refine_noise = 2;        ///< the spread refine judges is what exceeds refine_noise x the records' own noise variance; 0 = raw
    float refine_band = 1;         ///< the gather replaces the interpolation wholly from refine_band x refine (blended below); 1 = hard
    float refine_hold = 0.5f;  ///< a shot's fragment refined the frame before stays refined down to refine_hold x refine; 1 = no hysteresis
    float refine_hold_reach =
        3;                ///< ... a moving camera's: near (pixel footprints) a point refined the frame before; 0 = only a still camera's
    int refine_rays = 0;  ///< rays of such a gather; 0 = the gather's rays
    /// Records as a control variate (docs/gather.md): every fragment traces this many rays of its
    /// own and adds their unbiased correction of the records' directional prediction; 0 = off.
    int correction_rays = 0;
    CorrectionPrediction correction_prediction = CorrectionPrediction::Cells;  ///< what the records predict
    RecordSurface displaced_records = RecordSurface::Undisplaced;              ///< where records of displaced surfaces live
    float displacement_near = 10;      ///< un-displaced records: hits within this many displacement bounds do not shrink them
    float refine_tilt = 20;            ///< un-displaced records: a fragment whose normal tilts more than this (degrees) is refined; 0 = off
    float temporal_tolerance = 0.02f;  ///< frames of a shot: a kept record is redone once its irradiance may have moved by this fraction
    float temporal_refine_reuse = 0.35f;  ///< frames of a shot: refinement takes an earlier frame's gather this many pixels away (0 = off)
    /// Records' values filtered with their neighbours' before the shading pass interpolates them:
    /// the range kernel's width in the records' estimated noise (record_filter.h); 0 = off.
    float record_filter = 0;
    float temporal_filter = 0;  ///< frames of a shot: a redone record keeps this share of its previous value (0 = off)
    /// Records keep their bounce light per light, each light's colour and intensity factored out,
    /// and are placed as if every light were white at intensity 1: an edit of a light's colour or
    /// intensity then rescales the cached bounce light exactly (docs/lighting-tool.md).
    bool light_parts = false;
    bool operator==(const CacheSettings&) const = default;
    /// The settings the shading pass interpolates with.
    CacheSettings for_shading() const {
        CacheSettings s = *this;
        s.quality = quality / shading_reach;
        s.accuracy = accuracy * shading_reach;
        return s;
    }
};

/// How indirect light reaches the BRDF.
struct ShadingSettings {
    bool light_per_channel = false;        ///< three (radiance, direction) pairs, not one
    LayerSet layers = LayerSet::Standard;  ///< Components: the beauty's parts, per light, and ids
    int specular_depth = 4;                ///< mirror and glass bounces a path from the camera follows (0 = none)
    SpecularHitLight indirect_at_specular_hits = SpecularHitLight::Cache;
    bool deep_colour = false;  ///< --deep-out also holds each fragment's shaded colour (R, G, B) for deep compositing
};

/// Threads, tiles and progressive output.
struct ParallelSettings {
    int threads = 0;                         ///< 0 = all cores
    int tile_size = 32;                      ///< tile (bucket) edge, pixels
    TileOrder tile_order = TileOrder::Rows;  ///< the order threads take tiles in
    CacheSharing cache_sharing = CacheSharing::Shared;
    bool preview = false;  ///< progressive gather-and-shade
};

/// How a frame's per-pixel passes lay out their work: the seed every random stream hashes
/// (VisibilitySettings::seed) and the tiles threads take (ParallelSettings). Not a stage's
/// settings: the plan resolves it once and hands it to every pass that works per pixel.
struct FrameTiling {
    uint64_t seed = 0;
    int tile_size = 32;
    TileOrder tile_order = TileOrder::Rows;
};

/// Everything under the scene file's "render" object, one struct per stage.
struct RenderSettings {
    VisibilitySettings visibility;
    DicingSettings dicing;
    LightingSettings lighting;
    RadiositySettings radiosity;
    IndirectSettings indirect;
    CacheSettings cache;
    ShadingSettings shading;
    ParallelSettings parallel;
};

}  // namespace bounce
