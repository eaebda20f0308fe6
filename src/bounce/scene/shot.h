// The shot a scene file describes: its frames and frame rate (keyframes.h reads it).
#pragma once

namespace bounce {

struct ShotSettings {
    bool animated = false;  ///< the file has an "animation" block
    double fps = 24;
    int first = 1, last = 1;  ///< frames of the shot (a still: 1-1)
    bool contains(double frame) const { return frame >= first && frame <= last; }
};

}  // namespace bounce
