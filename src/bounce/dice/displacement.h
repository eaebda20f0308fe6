// Displacement maps: a scalar height per uv, read through OpenImageIO's texture system
// (tiled, cached, bilinear on the finest MIP level: dicing samples at micropolygon vertices).
#pragma once

#include <memory>
#include <string>

#include "bounce/core/math.h"

namespace bounce {

class DisplacementMap {
  public:
    /// Opens `path` (throws InputError naming it when it is missing or not an image).
    explicit DisplacementMap(const std::string& path);
    ~DisplacementMap();
    DisplacementMap(const DisplacementMap&) = delete;
    DisplacementMap& operator=(const DisplacementMap&) = delete;

    /// Height in [0, 1] for 8-bit maps (the first channel), at uv (v up, as OBJ writes it);
    /// wraps outside [0, 1].
    float height(const Vec2& uv) const;
    const std::string& path() const { return path_; }

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
    std::string path_;
};

}  // namespace bounce
