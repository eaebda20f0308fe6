// Reading an object's "fur" block (docs/fur.md, docs/scene-format.md): parameters checked as
// the types they are used in, density and length maps loaded, the memory the strands would take
// checked against render.memory_budget before any is grown.
#pragma once

#include <memory>

#include "bounce/geometry/fur.h"
#include "bounce/scene/json_reader.h"
#include "bounce/scene/scene.h"

namespace bounce {

/// The keys a "fur" block may have.
const std::vector<std::string>& fur_keys();
/// Those of them that only change how strands are lit, not where they are: a deep file does
/// not depend on them (Scene::visibility_fingerprint).
const std::vector<std::string>& fur_lighting_keys();

/// Reads `r` (the object's "fur" block) and grows the fur on `surface`.
std::shared_ptr<Fur> read_fur(const JsonReader& r, const TriangleMesh& surface, const DicingSettings& dicing);

}  // namespace bounce
