// bounce.Image: a render's layers as NumPy arrays that view the renderer's own buffers (no
// copy; each array keeps the image alive), its window in the full frame, metadata and the
// frame's statistics.
#pragma once

#include <pybind11/pybind11.h>

#include <memory>

#include "bounce/core/image.h"

namespace bounce::python {

/// The Python image for `image`, with `stats` (a dict, or empty) as its .stats.
pybind11::object wrap_image(std::shared_ptr<Image> image, pybind11::dict stats);

/// The image a bounce.Image holds; InputError(call) for anything else.
std::shared_ptr<const Image> image_of(pybind11::handle value, const std::string& call);

void add_image(pybind11::module_& m);

}  // namespace bounce::python
