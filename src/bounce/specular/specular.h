// Mirrors and glass (docs/shading.md): how a material splits the light at a smooth surface
// (an ideal mirror's share, Fresnel reflection and refraction of a dielectric, the rest for its
// diffuse and glossy lobes), and the specular paths that leave a visible fragment, followed
// through reflections and refractions for up to render.specular_depth bounces to the surfaces
// where they end (sites). Paths use no random numbers: the gathering pass and the shading pass
// trace the same ones, so the cache can cover every site before the shading pass runs.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "bounce/accel/accel.h"
#include "bounce/core/progress.h"
#include "bounce/core/stats.h"
#include "bounce/deep/deep_buffer.h"
#include "bounce/lighting/lighting.h"

namespace bounce {

/// The first bounce of a path: what compositing layers it goes to.
enum class PathKind : uint8_t { Reflection, Refraction };

/// Where a specular path ends on a surface that reflects light with its own lobes.
struct PathSite {
    /// The surface as a fragment: p, n and ng facing the path, p_base = p and n_base = n,
    /// uv, object, material, the coarse triangle, depth = the path's length, weight 1 and
    /// the path's pixel footprint (the camera pixel's cone over the whole length).
    Fragment at;
    Color weight{0};     ///< what the path lets through (mirror and Fresnel shares, tints, absorption) x the base share there
    Vec3 wo;             ///< unit, back along the path
    float u = 0, v = 0;  ///< barycentrics on the coarse triangle (radiosity textures)
    bool front = true;   ///< the path met the triangle's front side
    PathKind kind = PathKind::Reflection;
    uint32_t fragment = 0;  ///< which of the pixel's fragments the path leaves
};

/// A pixel's specular paths.
struct PixelPaths {
    std::vector<PathSite> sites;  ///< at most kMaxSitesPerPixel, in trace order
    /// Per fragment of the pixel: radiance its paths met without ending on a surface (the sky,
    /// quad lights), by kind, and the fragment's own base share (1 for a non-specular surface).
    std::vector<Color> seen_reflection, seen_refraction, base;
    uint32_t rays = 0;  ///< traced so far for this pixel (at most kMaxRaysPerPixel)
    void clear() { sites.clear(), seen_reflection.clear(), seen_refraction.clear(), base.clear(), rays = 0; }
};
/// A site's index within its pixel is a byte of its cache candidate key (cache/sites.h).
inline constexpr size_t kMaxSitesPerPixel = 255;
/// A pixel's specular rays: glass at grazing angles splits every path in two at each of up to
/// 16 bounces; past this many rays a pixel's remaining branches are dropped (in trace order).
inline constexpr uint32_t kMaxRaysPerPixel = 4096;

class SpecularTracer {
  public:
    /// `materials` tilt a fragment's mirror normal by its bump or normal map; `depth`: the
    /// bounces a path follows (ShadingSettings::specular_depth).
    SpecularTracer(const Scene& scene, const SceneAccel& accel, const DirectLighting& lighting, const Materials& materials, int depth);
    /// Whether any material is a mirror or glass (with render.specular_depth 0 their base shares still apply).
    bool active() const { return active_; }
    /// The paths leaving the fragments of one pixel, seen from `eye`. Branches whose weight
    /// falls below 1e-4 are dropped; a pixel's sites beyond kMaxSitesPerPixel and its rays
    /// beyond kMaxRaysPerPixel too.
    void trace(std::span<const Fragment> frags, const Vec3& eye, PixelPaths& out, Counters& counters) const;

  private:
    struct Branch;
    /// Where a fragment's paths start: a point and the shading and geometric normals (both outwards).
    struct Start {
        Vec3 p, n, outward;
    };
    Start start_of(const Fragment& f, const Vec3& d) const;
    /// `at`'s normal tilted as the fragment's bump or normal map tilts its own, for a camera ray along `d`.
    Vec3 bumped(const Fragment& f, const Start& at, const Vec3& d) const;
    void follow(const Branch& b, PixelPaths& out, Counters& counters) const;
    /// Continues a branch that met a specular surface: its reflected and refracted branches.
    void split(const Branch& b, const Vec3& p, const Vec3& n, bool entering, const Material& m, float travelled, PixelPaths& out,
               Counters& counters) const;
    /// Radiance of the quad lights a ray from o along d meets before distance `t_max`.
    Color quads_seen(const Vec3& o, const Vec3& d, float t_max) const;

    const Scene& scene_;
    const SceneAccel& accel_;
    const DirectLighting& lighting_;
    const Materials& materials_;
    int depth_ = 0;
    bool active_ = false;
};

/// Every pixel's sites, as the fragments of a deep buffer over `deep`'s window (per pixel in
/// trace order): what the gathering pass covers with records, traced in tiles of `tile_size`.
DeepBuffer specular_sites(const Scene& scene, const DeepBuffer& deep, const SpecularTracer& tracer, int tile_size, Stats& stats,
                          ProgressSink* progress);

}  // namespace bounce
