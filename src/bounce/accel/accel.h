// Ray tracing: Embree BVHs over the coarse tessellation (all secondary rays) and the fine one
// (primary visibility), and ray-origin offsetting between the two (TL04).
#pragma once

#include <embree3/rtcore.h>

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "bounce/core/math.h"
#include "bounce/scene/scene.h"

namespace bounce {

inline constexpr uint32_t kNoHit = 0xffffffffu;

/// Ray masks (Embree: a ray sees a geometry when their masks share a bit). Objects carry the
/// bits of the rays that see them (Object::visible_to); a light with a shadow link has a bit
/// of its own (kRayShadowLink << Light::shadow_slot) that only the objects casting its shadows hold.
/// Mirror and glass rays take the top bit, above the shadow links' (kMaxShadowLinkedLights).
inline constexpr unsigned kRayCamera = 1u, kRayShadow = 2u, kRayIndirect = 4u, kRayShadowLink = 8u, kRayReflect = 1u << 31,
                          kRayAll = ~0u;
static_assert((kRayShadowLink << (kMaxShadowLinkedLights - 1)) < kRayReflect);
/// The mask of object `index`'s geometry.
unsigned object_ray_mask(const Scene& scene, size_t index);
/// The same for object `index`'s fur (FurParams::visible_to).
unsigned fur_ray_mask(const Scene& scene, size_t index);
/// The mask of a shadow ray towards `light`.
inline unsigned shadow_ray_mask(const Light& light) {
    return light.shadow_slot < 0 ? kRayShadow : kRayShadowLink << light.shadow_slot;
}

struct Hit {
    float t = INFINITY;
    uint32_t object = kNoHit;  ///< index into Scene::objects
    uint32_t prim = 0;
    float u = 0, v = 0;
    bool hair = false;         ///< a fur segment of `object` (prim = segment, u along it)
    bool valid() const { return object != kNoHit; }
};

/// One Embree scene over a list of meshes (geometry id = index in the list) and, optionally,
/// fur: `furs[i]` (null = none) is object i's, traced as flat linear curves whose hits say
/// `hair` and name object i.
class Bvh {
public:
    /// `motion[i]` (if given and not null): mesh i's vertices at shutter open and close, traced
    /// with Embree's motion blur (ray time 0 = open, 1 = close). `masks[i]` (if given): mesh
    /// i's ray mask (else every ray sees it); `fur_masks[i]` likewise for fur i.
    Bvh(RTCDevice device, const std::vector<const TriangleMesh*>& meshes, const std::vector<const Fur*>& furs = {},
        const std::vector<const std::array<std::vector<Vec3>, 2>*>& motion = {}, const std::vector<unsigned>& masks = {},
        const std::vector<unsigned>& fur_masks = {});
    /// Meshes plus an instance of `fur`, a BVH of fur only over as many mesh ids (so its hits
    /// decode the same): fur traced by several BVHs is built once.
    Bvh(RTCDevice device, const std::vector<const TriangleMesh*>& meshes, const Bvh& fur,
        const std::vector<const std::array<std::vector<Vec3>, 2>*>& motion = {}, const std::vector<unsigned>& masks = {});
    ~Bvh();
    Bvh(const Bvh&) = delete;
    Bvh& operator=(const Bvh&) = delete;

    /// `time` in [0, 1] over the shutter (meshes without motion are where they are).
    Hit intersect(const Vec3& o, const Vec3& d, float tnear, float tfar, float time = 0, unsigned mask = kRayAll) const;
    /// Closest hits of `count` rays sharing origin `o` (a gather's hemisphere), traced in
    /// packets of 16: neighbouring strata are coherent enough for Embree's packet traversal.
    void intersect_from(const Vec3& o, const Vec3* d, size_t count, float tnear, Hit* out, unsigned mask = kRayAll) const;
    bool occluded(const Vec3& o, const Vec3& d, float tnear, float tfar, unsigned mask = kRayAll) const;

private:
    /// A new scene holding `meshes` (not committed).
    void begin(RTCDevice device, const std::vector<const TriangleMesh*>& meshes,
               const std::vector<const std::array<std::vector<Vec3>, 2>*>& motion, const std::vector<unsigned>& masks);
    Hit make_hit(unsigned geom, unsigned prim, float t, float u, float v) const;
    RTCScene scene_ = nullptr;
    unsigned mesh_count_ = 0;
};

/// Everything rays need from a scene: both BVHs and the offset distance.
class SceneAccel {
public:
    explicit SceneAccel(const Scene& scene);
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

    RTCDevice device_ = nullptr;
    std::unique_ptr<Bvh> coarse_, fine_;
    std::unique_ptr<Bvh> shadow_fur_;  ///< fur that casts shadows (null = none)
    float ray_offset_ = 0, gap_ = 0, min_epsilon_ = 0;
};

}  // namespace bounce
