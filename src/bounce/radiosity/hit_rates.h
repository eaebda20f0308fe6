// How often a frame's gathers hit each object, from a probe: what the small instances' choice
// between a lattice and light at the hit is measured by (RadiositySettings::small_instances).
#pragma once

#include <vector>

#include "bounce/accel/accel.h"
#include "bounce/scene/scene.h"

namespace bounce {

/// A probe of a frame's gathers: camera rays through a grid over the full frame find surfaces,
/// each sends cosine-distributed rays, and the hits are counted per object.
struct HitProbe {
    std::vector<double> hits;  ///< per object (by index)
    double slots = 0;          ///< the grid's pixels times the rays each (a pixel that sees the sky gathers nothing)
    /// What `rays` gather rays spread as the probe's would hit on `object`, at most (a one-sided
    /// 95 % bound: a Poisson count seen as n is below n + 3 for n = 0): an object the probe
    /// barely met is not taken for one the frame's gathers rarely reach.
    double hits_at_most(size_t object, double rays) const { return slots > 0 ? (hits.at(object) + 3) / slots * rays : 0; }
};

/// The probe over a grid of `grid` columns (rows to the frame's aspect), `rays` rays each: a
/// function of the scene alone, the same on every process, for every crop and re-render.
HitProbe probe_gather_hits(const Scene& scene, const SceneAccel& accel, int grid = 64, int rays = 32);

}  // namespace bounce
