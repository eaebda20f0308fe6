// Image layers made from more than the shading pass: the record dots.
#pragma once

#include <vector>

#include "bounce/core/image.h"
#include "bounce/scene/scene.h"

namespace bounce {

/// Adds a "records" layer: the beauty at half brightness with each record's position as a
/// white 3x3 dot.
void add_records_layer(Image& image, const Camera& camera, const std::vector<Vec3>& positions);

}  // namespace bounce
