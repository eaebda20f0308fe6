// What bounce reads of a glTF material from the file's JSON itself, where Assimp 5.2 reads it
// not at all or not as the specification says: KHR_materials_emissive_strength, the texture
// transform and uv set of each texture, KHR_materials_transmission, KHR_materials_ior and
// KHR_materials_diffuse_transmission, doubleSided; and, for every material, what is left unread (material_report.h names it).
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "bounce/scene/scene.h"

namespace bounce {

/// One glTF material's parts read from its JSON.
struct GltfMaterialJson {
    float emissive_strength = 1;
    /// Where its textures are read: the transform and uv set of its base colour texture (else
    /// its first texture's). A texture on another set or transform is not read (`skipped`,
    /// "occlusionTexture", ...: read at the wrong uvs it would be wrong, not missing) and is
    /// named in `unread`.
    UvTransform uv_transform;
    uint8_t uv_set = 0;
    std::vector<std::string> skipped;
    std::optional<float> transmission;    ///< KHR_materials_transmission's factor
    float ior = 1.5f;                     ///< KHR_materials_ior's (with transmission)
    float diffuse_transmission = 0;       ///< KHR_materials_diffuse_transmission's factor
    Color diffuse_transmission_color{1};  ///< and its colour factor
    /// Features bounce does not read ("KHR_materials_sheen", "COLOR_0 ..."), each once.
    std::vector<std::string> unread;
};

/// Every material of a .gltf or .glb file, by index (empty for other formats or a file without
/// materials). Throws InputError naming the file and the JSON pointer of a value out of range
/// (a transform that is not finite, an emissive strength beyond 1e20, a texCoord past 1, an
/// ior outside [1, 3], a transmission outside [0, 1]).
std::vector<GltfMaterialJson> read_gltf_materials(const std::string& path);
/// The same of file `path`'s JSON `doc`, already parsed.
std::vector<GltfMaterialJson> read_gltf_materials(const nlohmann::json& doc, const std::string& path);

}  // namespace bounce
