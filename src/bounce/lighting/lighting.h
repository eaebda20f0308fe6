// Direct lighting of diffuse surfaces with ray-traced shadows. Area lights, emissive meshes
// and the sky are sampled with stratified samples; every random number comes from a
// RandomStream. Materials (albedo, gloss, bump) are in materials.h.
#pragma once

#include <functional>
#include <memory>
#include <span>
#include <vector>

#include "bounce/accel/accel.h"
#include "bounce/config/settings.h"
#include "bounce/core/random.h"
#include "bounce/core/sampling.h"
#include "bounce/core/scratch.h"
#include "bounce/core/stats.h"
#include "bounce/lighting/materials.h"
#include "bounce/scene/scene.h"

namespace bounce {

/// Emissive triangles of one object, with an area CDF for sampling.
struct Emitter {
    uint32_t object = 0;
    std::vector<uint32_t> prims;
    std::vector<float> cdf;  ///< cumulative area, last = total
    float area = 0;
};

/// Called for each unshadowed light sample with its light (index into Scene::lights), its
/// direction (unit, from the point) and its share of the irradiance (the samples' shares sum
/// to the returned E): lets glossy BRDFs reuse the samples the diffuse estimate draws, and the
/// shading pass split the light per light.
using LightSampleFn = std::function<void(size_t light, const Vec3& w, const Color& e)>;

/// What each light's unit part is multiplied by (CacheSettings::light_parts): its colour times
/// its intensity, or 1 for a mesh light (its emission, a material's, stays in its part).
std::vector<Color> light_scales(const Scene& scene);

/// Direct lighting over all of a scene's lights.
class DirectLighting {
  public:
    /// `settings`: samples per light and how many lights a point picks (LightingSettings).
    DirectLighting(const Scene& scene, const SceneAccel& accel, const LightingSettings& settings);
    const LightingSettings& settings() const { return settings_; }

    /// Irradiance E arriving at `p` (on the fine surface of object `object`) through the
    /// hemisphere of unit normal `n`, from the lights linked to that object, with the shadows
    /// each light's shadow link lets fall. `samples` stratified samples per area light and for the sky.
    /// Diffuse radiance leaving the point is albedo * E / pi.
    /// `include_sky = false` leaves sky lights out (when the gather brings the sky instead).
    /// `hair_start` > 0: p is on a strand of that width (SceneAccel::occluded).
    Color irradiance(const Vec3& p, const Vec3& n, uint32_t object, const RandomStream& rng, int samples, Counters& counters,
                     bool include_sky = true, const LightSampleFn* each = nullptr, float hair_start = 0) const;

    /// The same irradiance per light with each light's scale (light_scales) factored out:
    /// out[i] (size: the scene's lights) is light i's unit part, 0 for a light not linked to
    /// `object`. Nothing in it depends on any light's colour or intensity.
    void irradiance_parts(const Vec3& p, const Vec3& n, uint32_t object, const RandomStream& rng, int samples, Counters& counters,
                          std::span<Color> out, float hair_start = 0) const;

    /// Diffuse radiance leaving a point of a thin surface on the side of unit normal `n`:
    /// reflect E(n) + transmit E(-n), for the BRDF `reflect` and BTDF `transmit` (albedo / pi
    /// and translucency / pi). The irradiance through the back hemisphere is drawn from
    /// back_side_stream(rng), and only where `transmit` is not 0. With `parts` (one per light):
    /// per light, scales factored out (irradiance_parts), and their sum is returned.
    Color diffuse_radiance(const Vec3& p, const Vec3& n, uint32_t object, const Color& reflect, const Color& transmit,
                           const RandomStream& rng, int samples, Counters& counters, std::span<Color> parts = {}) const {
        // An opaque side without light parts, the common case, in line: reflect E(n).
        if (parts.empty() && transmit == Color(0)) return reflect * irradiance(p, n, object, rng, samples, counters);
        return thin_or_parted_radiance(p, n, object, reflect, transmit, rng, samples, counters, parts);
    }

    /// Radiance a strand sends back along a ray of direction `d` that hit it (`h`, a hair hit) at
    /// `at`: its albedo x the direct light on the strand's side facing the ray / pi, as gathers
    /// and reflections see fur. With `parts` (one per light): per light, scales factored out
    /// (irradiance_parts), and their sum is returned.
    Color strand_radiance(const Hit& h, const Vec3& at, const Vec3& d, const RandomStream& rng, int samples, Counters& counters,
                          std::span<Color> parts = {}) const;
    /// Radiance the camera sees where a primary ray escapes (the sky; black without one).
    Color background(const Vec3& dir) const;
    /// The same per sky light, its scale factored out (0 for the other lights).
    void background_parts(const Vec3& dir, std::span<Color> out) const;
    const SceneAccel& accel() const { return accel_; }

  private:
    /// diffuse_radiance() of a translucent side, or with light parts.
    Color thin_or_parted_radiance(const Vec3& p, const Vec3& n, uint32_t object, const Color& reflect, const Color& transmit,
                                  const RandomStream& rng, int samples, Counters& counters, std::span<Color> parts) const;
    /// irradiance() over more pickable lights than LightingSettings::light_pick: that many
    /// picks among `pool`, each by its unshadowed contribution with a tenth spread evenly (so
    /// every light that may light p can be chosen), weighed by one over its chance.
    Color picked_irradiance(std::span<const size_t> pool, const Vec3& p, const Vec3& n, const RandomStream& rng, int samples,
                            Counters& counters, const LightSampleFn* each, float hair_start, ScratchBuffer& scratch) const;
    /// `unit`: with the light's scale (light_scales) factored out.
    Color sample_light(size_t index, const Vec3& p, const Vec3& n, const RandomStream& rng, int samples, Counters& counters,
                       const LightSampleFn* each, float hair_start, bool unit = false) const;

    const Scene& scene_;
    const SceneAccel& accel_;
    LightingSettings settings_;
    std::vector<Emitter> emitters_;                      ///< parallel to scene.lights (empty for non-mesh lights)
    std::unique_ptr<PerThread<ScratchBuffer>> scratch_;  ///< many lights' pick pools, per thread
};

}  // namespace bounce
