// A mesh file's materials through Assimp, and what Assimp 5.2 does not read of a glTF's
// (cutouts' base colour alpha, KHR_materials_emissive_strength), checked as a scene file's are.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "bounce/scene/mesh_import.h"

struct aiScene;

namespace bounce {

/// The file's materials appended to `materials` (named "<prefix>/<name>"), or `override_material`
/// for all: the scene index of each of the file's materials. Textures they name pass `files_read`.
std::vector<uint32_t> import_materials(const aiScene* s, const std::string& path, const std::string& prefix,
                                       std::vector<Material>& materials, int override_material, MeshInputs* files_read);

}  // namespace bounce
