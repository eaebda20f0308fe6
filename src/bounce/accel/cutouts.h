// Cutouts in the BVHs (issue 61): an Embree filter on every mesh that has a cutout material
// decides, for each hit, whether the surface is there for that ray. Meshes without one get no
// filter, so opaque geometry traces as before.
#pragma once

#include <embree3/rtcore.h>

#include <cstdint>
#include <memory>
#include <vector>

#include "bounce/core/math.h"
#include "bounce/scene/scene.h"

namespace bounce {

/// What a filter needs to cut one mesh: its uvs and faces' materials and the cutouts of the
/// materials it uses, copied, so a BVH kept by a shot's later frames needs nothing of this one's scene.
class CutoutMesh {
  public:
    /// Null when no face of `mesh` has a cutout material (scene.materials).
    static std::shared_ptr<const CutoutMesh> make(const std::vector<Material>& materials, const TriangleMesh& mesh);
    /// What `make` would hold, hashed (0 when it would be null): a BVH part built with other
    /// cutouts is not taken over.
    static uint64_t key(const std::vector<Material>& materials, const TriangleMesh& mesh);

    AlphaMode mode(uint32_t prim) const { return cuts_[face_materials_[prim]].mode; }
    /// Opacity at barycentrics (u, v) of triangle `prim` (Embree's: p = (1-u-v) p0 + u p1 + v p2).
    float opacity(uint32_t prim, float u, float v) const;
    /// Whether the surface at (u, v) of `prim` stops a ray. Mask: opacity at or above the cutoff,
    /// for every ray. Blend: camera rays stop wherever opacity is above 0 (the camera takes its
    /// share as coverage); other rays stop with probability opacity, drawn from `ray_hash`.
    bool stops(uint32_t prim, float u, float v, bool camera, uint64_t ray_hash) const;
    /// Sets the filter on Embree geometry `g` (intersect and occluded) with this as its user data.
    void attach(RTCGeometry g) const;

  private:
    struct Cut {
        AlphaMode mode = AlphaMode::Opaque;
        float opacity = 1, cutoff = 0.5f;
        std::shared_ptr<const OpacityMap> map;
    };
    std::vector<Cut> cuts_;  ///< per material index (what the mesh's faces name)
    std::vector<Vec2> uvs_;  ///< per vertex (empty: none, opacity is the material's alone)
    std::vector<uint32_t> indices_, face_materials_;
};

}  // namespace bounce
