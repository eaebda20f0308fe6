// Embree BVHs: one scene of meshes and fur, or of other BVHs placed with a transform (two-level:
// a shot's static set built once, moving objects placed anew each frame, deforming ones refit).
#pragma once

#include <embree3/rtcore.h>

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "bounce/accel/cutouts.h"
#include "bounce/core/math.h"
#include "bounce/geometry/fur.h"
#include "bounce/geometry/mesh.h"
#include "bounce/scene/scene.h"

namespace bounce {

inline constexpr uint32_t kNoHit = 0xffffffffu;

/// Ray masks (Embree: a ray sees a geometry when their masks share a bit). Objects carry the
/// bits of the rays that see them (Object::visible_to); a light with a shadow link has a bit
/// of its own (kRayShadowLink << Light::shadow_slot) that only the objects casting its shadows hold.
/// Mirror and glass rays take the top bit, above the shadow links' (kMaxShadowLinkedLights).
inline constexpr unsigned kRayCamera = 1u, kRayShadow = 2u, kRayIndirect = 4u, kRayShadowLink = 8u, kRayReflect = 1u << 31, kRayAll = ~0u;
static_assert((kRayShadowLink << (kMaxShadowLinkedLights - 1)) < kRayReflect);
/// The mask of object `index`'s geometry.
unsigned object_ray_mask(const Scene& scene, size_t index);
/// The same for object `index`'s fur (FurParams::visible_to).
unsigned fur_ray_mask(const Scene& scene, size_t index);
/// The mask of a shadow ray towards `light`.
inline unsigned shadow_ray_mask(const Light& light) { return light.shadow_slot < 0 ? kRayShadow : kRayShadowLink << light.shadow_slot; }

struct Hit {
    float t = INFINITY;
    uint32_t object = kNoHit;  ///< index into Scene::objects
    uint32_t prim = 0;
    float u = 0, v = 0;
    bool hair = false;  ///< a fur segment of `object` (prim = segment, u along it)
    bool valid() const { return object != kNoHit; }
};

/// Vertex positions at shutter open and close of a mesh that moves in the shutter.
using ShutterPositions = std::array<std::vector<Vec3>, 2>;
/// Fur control points (x, y, z, radius, as Fur::vertices) at shutter open and close.
using FurShutter = std::array<std::vector<float>, 2>;

/// What a BVH of meshes and fur holds, per id (an object's index); every list may be shorter
/// than `meshes` (missing entries: none, still, every ray).
struct BvhGeometry {
    std::vector<const TriangleMesh*> meshes;                 ///< geometry id = index (null: none)
    std::vector<const ShutterPositions*> motion;             ///< mesh i at shutter open and close (Embree's motion blur)
    std::vector<unsigned> masks;                             ///< mesh i's ray mask
    std::vector<std::shared_ptr<const CutoutMesh>> cutouts;  ///< mesh i's cutouts (null: none, no filter)
    std::vector<const Fur*> furs;                            ///< geometry id = meshes.size() + i: object i's fur
    std::vector<const FurShutter*> fur_motion;               ///< fur i at shutter open and close
    std::vector<unsigned> fur_masks;                         ///< fur i's ray mask
    /// Its meshes may later take new positions (`refit`); it holds its vertices itself.
    bool refittable = false;
};

/// One Embree scene over meshes and fur (fur traced as flat linear curves whose hits say `hair`
/// and name the object), or over other BVHs placed by a transform (instances): hits report the
/// placed BVH's own geometry ids, so every BVH of a scene decodes its hits the same way.
/// Motion blur: ray time 0 = shutter open, 1 = close; what does not move is where it is.
class Bvh {
  public:
    Bvh(RTCDevice device, const BvhGeometry& geometry);
    /// Meshes plus an instance of `fur`, a BVH of fur only over as many mesh ids (so its hits
    /// decode the same): fur traced by several BVHs is built once.
    Bvh(RTCDevice device, const BvhGeometry& meshes, const Bvh& fur);
    /// Other BVHs placed in this one (each over `mesh_count` mesh ids, as above).
    struct Placed {
        std::shared_ptr<const Bvh> bvh;
        std::array<Transform, 2> at;  ///< where it is at shutter open and close
        bool moving = false;          ///< at[1] differs from at[0]: Embree's motion blur
        unsigned mask = kRayAll;      ///< the rays that see it (and then its own geometry's masks)
        /// Hits in it report this object (an instance of a prototype's BVH); kNoHit: its own ids.
        uint32_t object = kNoHit;
    };
    Bvh(RTCDevice device, const std::vector<Placed>& placed, unsigned mesh_count);
    ~Bvh();
    Bvh(const Bvh&) = delete;
    Bvh& operator=(const Bvh&) = delete;

    /// New positions for mesh `id` of a refittable BVH (the same triangles; `motion` as in the
    /// constructor, null = none, as when it was built): Embree refits the BVH instead of
    /// building it. Call `commit` after the last. BVHs placing this one see the change only
    /// when they are built again, so the ones built before it are stale (`refits` counts).
    void refit(unsigned id, const TriangleMesh& mesh, const ShutterPositions* motion);
    void commit();
    /// How many times it was refit: a BVH placing it is current while this is what it was then.
    uint64_t refits() const { return refits_; }
    bool empty() const { return empty_; }

    /// `time` in [0, 1] over the shutter (meshes without motion are where they are).
    Hit intersect(const Vec3& o, const Vec3& d, float tnear, float tfar, float time = 0, unsigned mask = kRayAll) const;
    /// Closest hits of `count` rays sharing origin `o` (a gather's hemisphere), traced in
    /// packets of 16: neighbouring strata are coherent enough for Embree's packet traversal.
    void intersect_from(const Vec3& o, const Vec3* d, size_t count, float tnear, Hit* out, unsigned mask = kRayAll) const;
    bool occluded(const Vec3& o, const Vec3& d, float tnear, float tfar, unsigned mask = kRayAll) const;

  private:
    /// A new scene holding `g`'s meshes (not committed).
    void begin(RTCDevice device, const BvhGeometry& g);
    void add_fur(RTCDevice device, const BvhGeometry& g, size_t id);
    /// `instance`: the placed BVH the hit is in (RTC_INVALID_GEOMETRY_ID: none).
    Hit make_hit(unsigned geom, unsigned instance, unsigned prim, float t, float u, float v) const;
    RTCScene scene_ = nullptr;
    unsigned mesh_count_ = 0;
    bool empty_ = true;
    uint64_t refits_ = 0;
    std::vector<std::shared_ptr<const Bvh>> placed_;          ///< kept alive while this one traces them
    std::vector<uint32_t> object_of_;                         ///< per placed geometry id: Placed::object
    std::vector<std::shared_ptr<const CutoutMesh>> cutouts_;  ///< its filters' data, kept while it traces
};

}  // namespace bounce
