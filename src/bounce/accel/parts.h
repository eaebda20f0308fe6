// The parts of a two-level SceneAccel (accel.h): what each was built from, so that a shot's next
// frame takes over the ones whose content did not change and refits deforming meshes.
#pragma once

#include <functional>
#include <memory>
#include <vector>

#include "bounce/accel/accel.h"

namespace bounce {

/// One part and what it was built from.
struct BvhPart {
    std::shared_ptr<Bvh> bvh;                      ///< null: nothing to trace
    uint64_t key = 0;                              ///< hash of everything it was built from
    uint64_t layout = 0;                           ///< what a refit keeps (triangles, time steps); 0: it cannot be refit
    uint64_t refits = 0;                           ///< bvh->refits() when this frame took it
    std::vector<std::shared_ptr<const Fur>> furs;  ///< whose buffers it traces (shared, not copied)
};

/// A scene's fur by the rays that see it (FurParams::visible_to), per object (null: none): the
/// camera's; gathers' and mirrors' (with `masks`, in the coarse BVH); shadows' where it is not
/// in the coarse BVH. `motion`: each fur at shutter open and close, for the camera.
struct FurLists {
    explicit FurLists(const Scene& scene);
    std::vector<const Fur*> visible, indirect, shadow;
    std::vector<unsigned> masks;
    std::vector<const FurShutter*> motion;
    static bool any(const std::vector<const Fur*>& furs);
};

class BvhParts {
  public:
    /// The parts of `scene`'s BVHs; those of `before` (the previous frame's) are taken over
    /// where their key matches, and refit where only positions changed.
    BvhParts(RTCDevice device, const Scene& scene, const BvhParts* before);

    /// The BVH secondary rays trace: every part placed.
    std::unique_ptr<Bvh> coarse(RTCDevice device, const Scene& scene) const;
    /// The one primary visibility traces; null when it would be the coarse one.
    std::unique_ptr<Bvh> fine(RTCDevice device, const Scene& scene) const;
    /// Fur that casts shadows but is not in the coarse BVH (null: none).
    std::shared_ptr<const Bvh> shadow_fur() const { return shadow_fur_.bvh; }

    /// Mover `id`'s own coarse part (a rigid mover's is before its placement; null: not a mover).
    const Bvh* coarse_part(size_t id) const;

    /// A prototype's BVHs, built once for all its instances (its only mesh has id 0).
    struct Prototype {
        BvhPart coarse, fine;
        std::vector<uint32_t> instances;  ///< the objects that place it
    };
    const std::vector<Prototype>& prototypes() const { return prototypes_; }
    const BvhReuse& reuse() const { return reuse_; }
    /// No part it holds was refit since (by a later frame).
    bool current() const;

  private:
    BvhPart take(const BvhPart* before, uint64_t key, uint64_t layout, const std::function<std::shared_ptr<Bvh>()>& build,
                 const std::function<void(Bvh&)>& refit);
    void take_still(RTCDevice device, const Scene& scene, const BvhParts* before);
    void take_movers(RTCDevice device, const Scene& scene, const BvhParts* before);
    void take_fur(RTCDevice device, const Scene& scene, const BvhParts* before);
    void take_prototypes(RTCDevice device, const Scene& scene, const BvhParts* before);
    /// The instances' placements in the coarse or the fine BVH.
    void place_instances(const Scene& scene, bool fine, std::vector<Bvh::Placed>& placed) const;

    BvhPart still_coarse_, still_fine_;   ///< the objects that do not move
    std::vector<BvhPart> coarse_, fine_;  ///< per object: the movers'
    BvhPart coarse_fur_, fine_fur_, shadow_fur_;
    std::vector<Prototype> prototypes_;
    bool needs_fine_ = false;
    BvhReuse reuse_;
};

}  // namespace bounce
