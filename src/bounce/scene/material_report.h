// What a mesh file's materials carry that bounce does not read (issue 61): named once per file,
// so nothing is dropped in silence.
#pragma once

#include <string>
#include <vector>

namespace bounce {

/// One feature a file's materials (or meshes) carry that bounce does not read, and how many use it.
struct UnreadFeature {
    std::string what;  ///< "KHR_materials_clearcoat", "emissiveTexture", "MTL map_Ks"
    int count = 0;
    std::string unit;                    ///< "material", "primitive", "file"
    std::vector<std::string> materials;  ///< the file's names of the materials that carry it (unit "material")
    std::string line() const;            ///< "emissiveTexture on 3 materials"
};

/// A glTF's (from its JSON) or an OBJ's (from its MTL files) unread material features; other
/// formats: none. The file has passed check_mesh_file (its JSON parses; its MTL files exist).
std::vector<UnreadFeature> unread_material_features(const std::string& path);

}  // namespace bounce
