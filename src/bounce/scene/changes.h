// What changed between two frames of a shot: which objects stayed, moved rigidly or deformed
// (and the space their motion swept), and whether lights, the sky or materials changed. The
// frame's plan reads it to keep BVHs, radiosity texels and cache records, move them, or redo
// them (docs/animation.md).
#pragma once

#include <cstdint>
#include <vector>

#include "bounce/core/math.h"
#include "bounce/scene/scene.h"

namespace bounce {

struct ObjectMotion {
    enum class Kind : uint8_t {
        Static,     ///< the surfaces rays trace are where they were
        Rigid,      ///< only its placement changed: `delta` maps last frame's world to this one's
        Deforming,  ///< its shape changed (a skin, morph targets, another dicing of its ray tessellation)
    };
    Kind kind = Kind::Static;
    Transform delta;
    Bounds swept;  ///< its world bounds in both frames: all its motion can touch
};

struct SceneChanges {
    /// The same objects with the same triangles (and cutouts) in both frames: anything at all may be kept.
    bool comparable = false;
    std::vector<ObjectMotion> objects;   ///< per object of this frame (when comparable)
    bool lights = false;                 ///< a light, an emissive material or the sky changed: every bake is redone
    bool sky = false;                    ///< the sky changed: every ray that escaped now sees another light
    bool camera = false;                 ///< the camera's pose or resolution changed: a pixel covers another footprint
    std::vector<uint8_t> materials;      ///< per material: 1 when its albedo (colour, texture) changed
    bool visible_geometry_same = false;  ///< also the fine tessellations and fur: BVHs may be kept
    bool moving() const;                 ///< any object not Static
};

/// Compares the scene of the previous frame with this frame's.
SceneChanges scene_changes(const Scene& before, const Scene& now);

}  // namespace bounce
