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
#include <vector>

#include "bounce/accel/accel.h"
#include "bounce/core/progress.h"
#include "bounce/core/stats.h"
#include "bounce/lighting/lighting.h"
#include "bounce/scene/scene.h"

namespace bounce {

/// Baked radiosity of one object's coarse triangles.
struct RadiosityMap {
    std::vector<uint8_t> level;     ///< per triangle lattice level n (>= 1)
    std::vector<uint32_t> offset;   ///< per triangle first lattice point
    std::vector<Color> front, back; ///< radiosity per lattice point, on each side of ng

    /// Radiosity at barycentrics (u, v) of triangle `prim`, on the side `front_side`.
    Color lookup(uint32_t prim, float u, float v, bool front_side) const;
};

class RadiosityTextures {
public:
    /// Bakes every object's radiosity (in parallel over triangles).
    static RadiosityTextures bake(const Scene& scene, const Materials& materials,
                                  const DirectLighting& lighting, const RadiositySettings& settings,
                                  Stats& stats, ProgressSink* progress);
    /// Writes one EXR per object into `dir` (created if needed), atomically.
    void save(const std::string& dir) const;
    /// Loads textures baked for exactly this scene, lights and settings; returns false (with
    /// `why`) if any file is missing or was baked for something else. Corrupt files throw.
    static bool load(const std::string& dir, const Scene& scene, const RadiositySettings& settings,
                     RadiosityTextures& out, std::string& why);

    /// Hash of what the bake depends on: geometry, materials, lights, settings.
    static uint64_t fingerprint(const Scene& scene, const RadiositySettings& settings);

    const RadiosityMap& object(uint32_t id) const { return maps_[id]; }
    size_t lattice_points() const;

private:
    std::vector<RadiosityMap> maps_;
    std::vector<std::string> names_;
    uint64_t fingerprint_ = 0;
    float texel_size_ = 0;
};

/// The lattice level a triangle with longest edge `edge` gets for lattice spacing `texel`.
int radiosity_level(float edge, float texel, int max_level);

}  // namespace bounce
