// Checks a mesh file must pass before Assimp reads it: what a hostile or broken file could do
// to the importer (a PLY header declaring 4e9 vertices, a glTF node chain 20 000 deep, a
// million-level JSON nesting, a million MTL materials, a truncated .glb) is refused here with
// the file and the place (exit 2), never left to a crash, a bad_alloc or a minutes-long load.
#pragma once

#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace bounce {

/// Deepest glTF node hierarchy accepted (Assimp recurses once per level).
inline constexpr int kMaxNodeDepth = 1000;
/// Most materials one OBJ's MTL files may define.
inline constexpr int kMaxMtlMaterials = 65536;

/// What a mesh file's checks need from the caller.
struct MeshCheckOptions {
    /// Called with each file the mesh names before anything opens it (the lighting tool's
    /// confinement: a file outside is refused unread).
    std::function<void(const std::string&)> before_open;
    /// The file's own materials are used (no scene material replaces them): an OBJ's missing
    /// MTL is then an error, not Assimp's silent default material.
    bool own_materials = true;
};

/// Runs the checks that apply to `path`'s format; returns the files it names that Assimp will
/// read too (a glTF's buffers and images, an OBJ's MTL files), resolved.
std::vector<std::string> check_mesh_file(const std::string& path, const MeshCheckOptions& options = {});

/// Whether `path` names a glTF file (.gltf or .glb, by its extension).
bool is_gltf_file(const std::string& path);

/// A .gltf file, or a .glb with its JSON and BIN chunks found (read once).
struct GltfFile {
    std::string bytes;
    size_t json_at = 0, json_size = 0, bin_at = 0, bin_size = 0;  ///< bin_size 0: no BIN chunk
    std::string_view json() const { return std::string_view(bytes).substr(json_at, json_size); }
    std::string_view bin() const { return std::string_view(bytes).substr(bin_at, bin_size); }
};
/// Reads `path`; InputError for a truncated or foreign .glb.
GltfFile read_gltf_file(const std::string& path);
/// The JSON text of a .gltf file or of a .glb's JSON chunk; InputError as read_gltf_file.
std::string gltf_json_text(const std::string& path);

/// A PLY whose header declares more elements than its body can hold is refused: ASCII by
/// counting lines, binary by the bytes its elements need.
void check_ply_counts(const std::string& path);

}  // namespace bounce
