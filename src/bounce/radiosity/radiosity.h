// Radiosity textures (TL04's name: baked radiosity, not the radiosity method): the direct light
// leaving each diffuse surface, albedo x E_direct / pi, baked at low resolution on the coarse
// tessellation so that gather rays shade their hits with one lookup instead of shadow rays.
//
// Layout: an automatic per-triangle atlas. Triangle t gets a barycentric lattice of level
// n_t (the triangle split n_t x n_t ways; (n_t+1)(n_t+2)/2 points), n_t chosen so lattice
// spacing is about `texel_size`; values are interpolated linearly inside each sub-triangle.
// Each side of a surface has its own value (both sides of a wall can be lit).
#pragma once

#include <cstdint>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include <atomic>
#include <memory>
#include <span>

#include "bounce/accel/accel.h"
#include "bounce/core/progress.h"
#include "bounce/core/random.h"
#include "bounce/core/stats.h"
#include "bounce/lighting/lighting.h"
#include "bounce/radiosity/hit_rates.h"
#include "bounce/radiosity/lattice.h"
#include "bounce/scene/changes.h"
#include "bounce/scene/scene.h"

namespace bounce {

/// An array that maps share when their layouts are equal (instances of one prototype at
/// similar scales: docs/instancing.md), read as a vector.
template <class T>
class SharedArray {
  public:
    SharedArray() : v_(std::make_shared<const std::vector<T>>()) {}
    explicit SharedArray(std::shared_ptr<const std::vector<T>> v) : v_(std::move(v)) {}
    const T& operator[](size_t i) const { return (*v_)[i]; }
    const T& at(size_t i) const { return v_->at(i); }
    size_t size() const { return v_->size(); }
    const std::vector<T>& vec() const { return *v_; }
    const std::shared_ptr<const std::vector<T>>& shared() const { return v_; }

  private:
    std::shared_ptr<const std::vector<T>> v_;
};

/// Baked radiosity of one object's coarse triangles.
struct RadiosityMap {
    SharedArray<uint8_t> level;    ///< per triangle lattice level n (>= 1)
    SharedArray<uint32_t> offset;  ///< per triangle first lattice point
    LatticeSide front, back;       ///< radiosity per lattice point, on each side of ng (sparse)
    /// CacheSettings::light_parts: per lattice point, `lights` unit parts (light_scales factored
    /// out) whose scaled sum is front / back.
    LatticeSide front_parts, back_parts;
    uint32_t lights = 0;
    /// A small instance lit where gather rays land (RadiositySettings::small_instances): never
    /// baked, its lookups trace shadow rays.
    bool lit_at_hit = false;
    /// Sides whose bake states it keeps (none when lit at the hit).
    size_t sides_baked_apart() const { return lit_at_hit ? 0 : 2 * level.size(); }

    /// Radiosity at barycentrics (u, v) of triangle `prim`, on the side `front_side`.
    Color lookup(uint32_t prim, float u, float v, bool front_side) const;
    /// The same per light (`out`: one per light; the map must hold parts).
    void lookup_parts(uint32_t prim, float u, float v, bool front_side, std::span<Color> out) const;
};

/// Radiosity that changed from one frame to the next in a region of space: a re-baked side
/// whose lattice values moved by up to `delta` (luminance of radiance) inside `bounds`.
struct LightChange {
    /// `triangle` of a small instance lit at the hit (never baked): all its triangles may have
    /// changed, by an unknown amount (`delta` the largest float).
    static constexpr uint32_t kEveryTriangle = 0xffffffffu;
    Bounds bounds;
    float delta = 0;
    uint32_t object = 0, triangle = 0;  ///< the re-baked side's triangle
};

/// Radiosity textures of every object. A triangle side's lattice is baked on the first lookup
/// that needs it (lazily), or all at once by bake_all(); its values depend only on the scene
/// (random numbers keyed by object, triangle and lattice point), so images never depend on
/// which thread baked what first.
class RadiosityTextures {
  public:
    RadiosityTextures();
    ~RadiosityTextures();
    RadiosityTextures(RadiosityTextures&&) noexcept;
    RadiosityTextures& operator=(RadiosityTextures&&) noexcept;

    /// Lays out every object's lattices; nothing is baked yet. `materials` and `lighting` must
    /// outlive the textures' lookups.
    static RadiosityTextures lazy(const Scene& scene, const Materials& materials, const DirectLighting& lighting,
                                  const RadiositySettings& settings);
    /// Lays out and bakes every lattice (in parallel over triangles).
    static RadiosityTextures bake(const Scene& scene, const Materials& materials, const DirectLighting& lighting,
                                  const RadiositySettings& settings, Stats& stats, ProgressSink* progress);
    /// Bakes every side not baked yet (needs the lazy sources); with `shares` > 1, only the
    /// triangles of share `share` (every shares-th triangle, counted over all objects), for the
    /// processes of an MPI job that split the bake and exchange the sides (take_baked).
    void bake_all(Stats& stats, ProgressSink* progress, int share = 0, int shares = 1);
    /// Writes one EXR per object into `dir` (created if needed), atomically; sides not baked
    /// are marked so and baked by whoever loads them.
    void save(const std::string& dir) const;
    /// Loads textures baked for exactly this scene, lights and settings; returns false (with
    /// `why`) if any file is missing or was baked for something else. Corrupt files throw.
    /// Sides the files do not hold are baked lazily from `materials` and `lighting`.
    static bool load(const std::string& dir, const Scene& scene, const RadiositySettings& settings, const Materials& materials,
                     const DirectLighting& lighting, RadiosityTextures& out, std::string& why);

    /// The previous frame's textures carried to this frame's `scene` (docs/animation.md): the same
    /// layout (texel size and levels, so texels keep their place) and values, but for deforming
    /// objects, laid out anew for their shape and baked lazily, as a frame rendered alone
    /// would (a stretched triangle gets another level); each side baked
    /// before is baked again now, in parallel, when `changes` says its direct light may differ:
    /// its object moved or deformed, its material or any light changed, or a moving object's
    /// swept bounds come between it and a light. Sides never baked stay lazy. `changed` receives
    /// the re-baked sides whose values moved, with by how much. `previous` is left as it was.
    static RadiosityTextures carry(const RadiosityTextures& previous, const Scene& scene, const Materials& materials,
                                   const DirectLighting& lighting, const RadiositySettings& settings, const SceneChanges& changes,
                                   std::vector<LightChange>& changed, Stats& stats);
    /// The sides baked here, with their values, as bytes for the other processes of an MPI job
    /// (docs/parallel.md), and taking theirs: sides are baked lazily by each process's own
    /// gathers, and a shot's next frame (which sides changed, the brightest texel) and a saved
    /// texture must not depend on which process baked what. Values are the same wherever baked.
    std::string baked_bytes() const;
    void take_baked(const std::string& bytes);
    /// The largest radiance (luminance) any baked side holds (the largest float with a small
    /// instance lit at the hit: its light is not known in advance).
    float brightest() const;

    /// Hash of what the bake depends on: geometry, materials, lights, settings (`light_samples`:
    /// the lighting's, which a bake takes where its own are 0).
    static uint64_t fingerprint(const Scene& scene, const RadiositySettings& settings, int light_samples);

    /// Radiosity of object `id` at barycentrics (u, v) of triangle `prim`, on side `front`;
    /// bakes that side first if needed (its shadow rays count in `counters`). A small instance
    /// lit at the hit (RadiosityMap::lit_at_hit) gets one light sample per light there, with
    /// random numbers keyed by the hit itself: the same hit has the same value however reached.
    Color lookup(uint32_t id, uint32_t prim, float u, float v, bool front, Counters& counters) const;
    /// The same per light, each light's scale factored out (textures of a scene with light_parts).
    void lookup_parts(uint32_t id, uint32_t prim, float u, float v, bool front, Counters& counters, std::span<Color> out) const;
    bool has_parts() const { return sources_ && !sources_->scales.empty(); }
    /// The baked map of object `id` (only the sides baked so far hold values).
    const RadiosityMap& object(uint32_t id) const { return maps_[id]; }
    size_t lattice_points() const;
    /// Bytes of lattice values allocated so far (pages of baked sides, lattice.h).
    size_t allocated_bytes() const;
    /// Objects lit at the hit (RadiosityMap::lit_at_hit).
    size_t objects_lit_at_hit() const;
    /// Triangle sides baked so far, and in all.
    size_t baked_sides() const;
    size_t sides() const;

  private:
    /// What a lazy bake reads (this frame's).
    struct Sources {
        const Scene* scene;
        const Materials* materials;
        const DirectLighting* lighting;
        int light_samples;          ///< resolved (never 0)
        std::vector<Color> scales;  ///< light_parts: every light's (light_scales); else empty
    };
    /// Object `id`'s map laid out for its shape in `scene`, nothing baked (with room for light
    /// parts); its level and offset arrays shared with an earlier map's when equal.
    RadiosityMap laid_out(const Scene& scene, size_t id, const RadiositySettings& settings, const HitProbe* probe = nullptr);
    /// Whether small instance `id` (level 1 throughout) is lit at the hit: as the settings say,
    /// or in auto by `probe` (null: keep the lattice).
    bool lit_at_hit(const Scene& scene, size_t id, const RadiositySettings& settings, const HitProbe* probe) const;
    /// Direct light leaving a small instance's side at the hit (RadiosityMap::lit_at_hit); with
    /// `parts`, per light as lookup_parts.
    Color light_at_hit(uint32_t id, uint32_t prim, float u, float v, bool front, Counters& counters, std::span<Color> parts) const;
    void bake_side(uint32_t id, uint32_t tri, bool front, Counters& counters) const;
    /// Direct light leaving side `front` of object `id` at `sp`, as a lattice point or a hit
    /// takes it; with light parts (the textures'), per light into `parts` and their scaled sum.
    Color side_radiance(uint32_t id, const SurfacePoint& sp, bool front, const RandomStream& rng, int samples, Counters& counters,
                        std::span<Color> parts) const;
    void ensure_baked(uint32_t id, uint32_t tri, bool front, Counters& counters) const;

    mutable std::vector<RadiosityMap> maps_;  ///< values written once per side, under its state flag
    mutable std::vector<SideStates> state_;   ///< per object, 2 per triangle: 0 new, 1 baking, 2 baked (lattice.h)
    std::vector<std::string> names_;
    /// Per mesh laid out so far, its longest edge in its own space (placements share their
    /// prototype's): a bound on their levels.
    std::unordered_map<const TriangleMesh*, float> longest_edges_;
    /// A lattice layout: levels and offsets.
    using Layout = std::pair<SharedArray<uint8_t>, SharedArray<uint32_t>>;
    /// Layouts laid out so far, by a hash of their levels (placements share theirs).
    std::unordered_map<uint64_t, std::vector<Layout>> layouts_;
    /// Per triangle count, the layout at level 1 throughout (laid out once for a forest).
    std::unordered_map<size_t, Layout> ones_;
    /// The layout of `level`, an earlier one's arrays when equal.
    Layout shared_layout(std::vector<uint8_t> level);
    std::unique_ptr<Sources> sources_;
    uint64_t fingerprint_ = 0;
    float texel_size_ = 0;
};

/// Points of a triangle's lattice of level n.
inline uint32_t lattice_count(int n) { return static_cast<uint32_t>((n + 1) * (n + 2) / 2); }

/// The lattice level a triangle with longest edge `edge` gets for lattice spacing `texel`.
int radiosity_level(float edge, float texel, int max_level);

}  // namespace bounce
