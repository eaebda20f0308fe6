// EXT_mesh_gpu_instancing: a glTF node that places its mesh many times, one TRS per instance
// read from accessors. Debian's Assimp 5.2 ignores the extension (the mesh would be placed
// once, silently), so bounce reads the attributes itself and matches the file's nodes to
// Assimp's. Internal to scene/: the mesh importer places these instances.
#pragma once

#include <assimp/scene.h>

#include <string>
#include <unordered_map>
#include <vector>

#include "bounce/core/math.h"

namespace bounce {

/// One node's instances.
struct GpuInstances {
    std::string pointer;        ///< "/nodes/N/extensions/EXT_mesh_gpu_instancing", for errors
    std::vector<Transform> at;  ///< per instance: translation x rotation x scale, in the node's space
};

/// The GPU instances of glTF file `path` (read by Assimp as `s`), per Assimp node; empty for
/// other formats and files without the extension. InputError with the place for a malformed
/// extension, accessor or buffer, values that are not finite, or a node tree Assimp did not
/// keep as the file's.
std::unordered_map<const aiNode*, GpuInstances> gltf_gpu_instances(const std::string& path, const aiScene* s);

}  // namespace bounce
