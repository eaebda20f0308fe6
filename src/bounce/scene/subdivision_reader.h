// Reading a mesh object with "subdivision" (object_reader.h): its control mesh through
// OpenSubdiv, diced from the camera into the fine tessellation and at render.ray_level into
// the coarse one, both displaced when it has a "displacement" (docs/displacement.md), the
// dicing refused before it is made when it cannot fit.
#pragma once

#include "bounce/dice/subdivision.h"
#include "bounce/scene/json_reader.h"
#include "bounce/scene/scene.h"

namespace bounce {

/// Object `obj` (read from `r`, its material `mat`, -1 = the file's own) diced with `scheme`.
void read_subdivision_object(const JsonReader& r, Scene& scene, int mat, Object& obj, SubdivScheme scheme, const DicingSettings& dicing);

}  // namespace bounce
