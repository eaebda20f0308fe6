// Ray tracing: Embree BVHs over the coarse tessellation (all secondary rays) and the fine one
// (primary visibility), and ray-origin offsetting between the two (TL04).
#pragma once

#include <embree3/rtcore.h>

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "bounce/accel/bvh.h"
#include "bounce/config/settings.h"
#include "bounce/core/math.h"
#include "bounce/scene/scene.h"

namespace bounce {

/// What a frame's BVHs took over from the previous frame's: parts whose content had not changed
/// (the static set, a rigid mover's shape), parts refit (a deforming mesh), parts built.
struct BvhReuse {
    int kept = 0, refit = 0, built = 0;
};

class BvhParts;

/// Everything rays need from a scene: both BVHs and the offset distance.
///
/// A scene in which nothing moves has one BVH of each kind over all its objects. When objects
/// move over a shot (Object::moves), each BVH is two-level: the static objects are one part,
/// every mover has its own — a rigid mover's built before its placement and placed with it, a
/// deforming one's refit when its triangles are the same — and fur is one more. A frame built
/// from the previous frame's takes over every part whose content is unchanged; a frame built
/// alone builds the same parts, so both trace alike, bit for bit.
class SceneAccel {
  public:
    /// `settings`: the ray offset's (LightingSettings::ray_offset, < 0 = measured from the two
    /// tessellations). `previous`: the shot's frame before (null: none) whose parts may be taken over.
    SceneAccel(const Scene& scene, const LightingSettings& settings, const SceneAccel* previous = nullptr);
    ~SceneAccel();
    SceneAccel(const SceneAccel&) = delete;
    SceneAccel& operator=(const SceneAccel&) = delete;

    const Bvh& coarse() const { return *coarse_; }
    /// The BVH primary visibility traces (the coarse one when no object has a finer one).
    const Bvh& fine() const { return fine_ ? *fine_ : *coarse_; }
    bool has_fine() const { return fine_ != nullptr; }

    /// Ray-origin offsetting distance delta in world units.
    float ray_offset() const { return ray_offset_; }
    /// Largest measured distance between a fine-tessellation vertex and its coarse surface.
    float fine_coarse_gap() const { return gap_; }
    /// What it took over from the previous frame's (all zero for one BVH of everything).
    BvhReuse reuse() const;
    /// False once a later frame refit a part it traces: then it no longer traces its own scene
    /// and may not be kept (FramePlan builds instead).
    bool current() const;

    /// Traces a gather ray (objects visible to indirect rays) that leaves the fine surface at `p` along unit `d`: the origin
    /// is moved to the coarse intersection closest to `p` within +-delta along the ray, and
    /// the first coarse hit after that origin is returned (t measured from `p`). Rays whose
    /// first hit from p is beyond delta take one traversal; only the others probe.
    /// `mask`: which objects the ray sees (kRayReflect: a mirror's or glass's ray).
    Hit trace(const Vec3& p, const Vec3& d, unsigned mask = kRayIndirect) const;
    /// `trace` for many directions from one point, in packets (the gather's path).
    void trace_many(const Vec3& p, std::span<const Vec3> dirs, std::span<Hit> out) const;
    /// Visibility from `p` (on the fine surface) to the point `p + d * dist` (dist may be
    /// INFINITY), with the same origin offsetting; the end point's own surface is excluded.
    /// Fur that casts shadows occludes too. From a strand (`hair_start` > 0, its largest
    /// width) there is no offsetting and fur closer than `hair_start` is ignored (its own strand).
    /// `mask`: which objects may occlude (shadow_ray_mask of the light).
    bool occluded(const Vec3& p, const Vec3& d, float dist, float hair_start = 0, unsigned mask = kRayShadow) const;

    /// Where the first, probe-free traversal from p starts: 1e-5 of p's largest coordinate
    /// (at least 1e-7 of the scene diagonal), above float rounding, far below delta.
    float self_epsilon(const Vec3& p) const;

  private:
    /// Parameter along the ray from p - delta*d at which the traced ray starts.
    float offset_start(const Vec3& p, const Vec3& d) const;
    /// The offset trace proper: from the coarse crossing nearest to p (t measured from p).
    Hit probed_trace(const Vec3& p, const Vec3& d, unsigned mask) const;

    /// One BVH of each kind over every object.
    void build_flat(const Scene& scene);
    /// Measures the fine/coarse gap and sets the offset distances.
    /// `ray_offset` < 0: measured from the gap between the two tessellations.
    void measure_offsets(const Scene& scene, float ray_offset);

    std::shared_ptr<RTCDeviceTy> device_;  ///< shared with the shot's later frames, whose parts it made
    std::unique_ptr<Bvh> coarse_, fine_;
    std::shared_ptr<const Bvh> shadow_fur_;  ///< fur that casts shadows (null = none)
    std::unique_ptr<BvhParts> parts_;        ///< two-level BVHs: their parts (null = flat)
    float ray_offset_ = 0, gap_ = 0, min_epsilon_ = 0;
};

}  // namespace bounce
