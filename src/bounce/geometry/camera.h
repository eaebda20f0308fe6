// The camera as plain data: where it stands and looks, its lens and shutter, its image size.
// It is part of the world (scene.h holds it) and the parameter table's camera rows read and
// write it (config/params.h), so it sits below both.
#pragma once

#include <array>

#include "bounce/core/math.h"

namespace bounce {

struct Camera {
    Vec3 position{0, 0, 5};
    Vec3 look_at{0, 0, 0};
    Vec3 up{0, 1, 0};
    float fov = 45.0f;  ///< vertical field of view, degrees
    int width = 512, height = 512;
    std::array<float, 2> shutter{0, 0};  ///< [open, close] in frames around the frame's time (motion blur)
    float aperture = 0;                  ///< lens diameter (depth of field); 0 = pinhole
    float focus_distance = 0;            ///< plane in focus along the view; 0 = the distance to look_at
    bool has_motion_blur() const { return shutter[1] > shutter[0]; }

    /// The keyable placement of a camera.
    struct Pose {
        Vec3 position, look_at, up;
        float fov = 45.0f;
        bool operator==(const Pose&) const = default;
    };
    Pose pose() const { return {position, look_at, up, fov}; }
    /// With motion blur: the pose at shutter open and close (set by the scene's loader).
    std::array<Pose, 2> shutter_pose{};
    /// A keyed camera that moves in the shutter: camera rays interpolate between its poses.
    bool moves_in_shutter() const { return has_motion_blur() && !(shutter_pose[0] == pose() && shutter_pose[1] == pose()); }
};

}  // namespace bounce
