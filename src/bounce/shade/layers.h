// Image layers made from more than the shading pass: the record dots.
#pragma once

#include <vector>

#include "bounce/core/image.h"
#include "bounce/deep/deep_buffer.h"
#include "bounce/scene/scene.h"

namespace bounce {

/// Adds a "records" layer: the beauty at half brightness with each record's position as a
/// white 3x3 dot.
void add_records_layer(Image& image, const Camera& camera, const std::vector<Vec3>& positions);

/// Adds a one-channel layer `name` (`name.Y`): per pixel, the coverage of its fragments whose
/// flag is set (e.g. the fragments refined with gathers of their own).
/// Per pixel of `deep`: the summed weight of its fragments whose flag (parallel to
/// deep.fragments) is set.
std::vector<float> fragment_mask(const DeepBuffer& deep, const std::vector<uint8_t>& flags);
/// Adds a one-channel layer `name` (`name`.Y) holding `mask`, one value per pixel.
void add_mask_layer(Image& image, const std::vector<float>& mask, const std::string& name);

}  // namespace bounce
