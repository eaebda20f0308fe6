// Mesh files through Assimp: every triangle of an OBJ/MTL, PLY, glTF 2.0 or other file with its
// node transforms and materials, and a bare file's own camera and punctual lights described as
// a JSON scene.
#pragma once

#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "bounce/dice/subdivision.h"
#include "bounce/scene/load_resources.h"
#include "bounce/scene/scene.h"

namespace bounce {

/// The other files a mesh file reads (an OBJ's MTL files and the textures they name, a glTF's
/// buffers and images): each is shown to `check` before Assimp or a texture reader opens it
/// (the loader's confinement, LoadOptions::check_path; it throws to refuse), then listed.
struct MeshInputs {
    std::function<void(const std::string& path)> check;
    std::vector<std::string> files;
    LoadResources resources;  ///< where the parse is kept (mesh cache) and embedded images written
    void add(const std::string& path) {
        if (check) check(path);
        files.push_back(path);
    }
};

/// Loads every triangle of a mesh file through Assimp (after mesh_checks.h's checks), node
/// transforms applied. Materials of the file are appended to `materials` (named
/// "<prefix>/<name>"; a base colour above 1, an emission that is not finite, or a texture that
/// is not there is an error) unless `override_material` is given, in which case every face uses
/// it. The other files it reads (MTL, buffers, textures) go through `files_read` (MeshInputs).
/// An animation of a mesh file to pose it with: the clip (name or number; empty: the rest pose)
/// and the time into it.
struct MeshPose {
    std::string clip;
    double seconds = 0;
};

TriangleMesh load_mesh_file(const std::string& path, const std::string& prefix, std::vector<Material>& materials, int override_material,
                            MeshInputs* files_read = nullptr, const MeshPose& pose = {});

/// A still mesh file's triangles split for instancing (docs/instancing.md): the meshes its nodes
/// use once, placed as load_mesh_file places them, and each mesh several nodes use (glTF shares
/// meshes between nodes) once in its own space, with every using node's name and world
/// transform. Skinned, morphed and emissive meshes are never shared.
struct MeshFileParts {
    struct Use {
        std::string node;
        Transform world;
    };
    struct Shared {
        TriangleMesh mesh;
        std::vector<Use> uses;
    };
    TriangleMesh once;
    std::vector<Shared> shared;
};
MeshFileParts load_mesh_parts(const std::string& path, const std::string& prefix, std::vector<Material>& materials, int override_material,
                              MeshInputs* files_read = nullptr);

/// Loads a mesh file's polygons as a subdivision control mesh (faces not triangulated,
/// vertices welded by position, uvs face-varying), node transforms and then `transform`
/// applied; materials as load_mesh_file.
ControlMesh load_control_mesh(const std::string& path, const std::string& prefix, std::vector<Material>& materials, int override_material,
                              const Transform& transform, MeshInputs* files_read = nullptr);

/// Describes a bare mesh file as a JSON scene: the file's camera and punctual lights.
nlohmann::json describe_mesh_file(const std::string& path);

}  // namespace bounce
