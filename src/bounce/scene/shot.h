// The shot a scene file describes: its frames and frame rate (keyframes.h reads it).
#pragma once

#include <fmt/format.h>

#include <cmath>
#include <string>

namespace bounce {

/// The largest frame number, keys' and the shot's (and --frame's) alike.
inline constexpr double kMaxFrame = 1e6;
inline bool is_frame_number(double frame) { return std::isfinite(frame) && std::fabs(frame) <= kMaxFrame; }

struct ShotSettings {
    bool animated = false;  ///< the file has an "animation" block
    double fps = 24;
    int first = 1, last = 1;  ///< frames of the shot (a still: 1-1)
    bool contains(double frame) const { return frame >= first && frame <= last; }
    /// The message refusing a frame outside the shot.
    std::string outside(double frame) const { return fmt::format("frame {:g} is outside the shot, frames {} to {}", frame, first, last); }
};

}  // namespace bounce
