// Animated mesh files (glTF through Assimp): node TRS channels, skins (joints and weights) and
// morph targets, sampled at a time of the shot (docs/animation.md). Internal to scene/: the
// mesh importer poses a file's meshes with it.
#pragma once

#include <assimp/scene.h>

#include <string>
#include <unordered_map>
#include <vector>

#include "bounce/core/error.h"
#include "bounce/core/math.h"

namespace bounce {

/// A mesh file has no clip of the name an object plays: the object's "animation" is at fault,
/// not its "file" (object_reader names the key by the type, not by the message).
class NoSuchClip : public InputError {
  public:
    using InputError::InputError;
};

/// Which animation of a mesh file plays, and when.
struct MeshTime {
    int clip = -1;       ///< index of the file's animation; -1: the rest pose (no animation)
    double seconds = 0;  ///< time into the clip (held at its ends)
};

/// The clip named `name` (or numbered: "0", "1" ...) of `s`; InputError(path) listing the
/// file's clips when there is none.
int find_clip(const aiScene* s, const std::string& name, const std::string& path);

/// Every node's world transform at `t` (its animation channels applied; the rest pose for
/// t.clip < 0). InputError(path) for a channel naming a node the file does not have.
std::unordered_map<const aiNode*, aiMatrix4x4> posed_nodes(const aiScene* s, const MeshTime& t, const std::string& path);

/// `mesh`'s vertices and normals posed: skinned by its bones (each joint's world transform
/// times its inverse bind matrix, weighted) and morphed by its targets' weights at `t`, else
/// moved by `node_world` like a rigid instance. InputError(path) for weights that are negative or
/// not finite, or joints naming vertices the mesh does not have.
void pose_mesh(const aiScene* s, const aiMesh* mesh, const MeshTime& t, const aiMatrix4x4& node_world,
               const std::unordered_map<const aiNode*, aiMatrix4x4>& nodes, std::vector<Vec3>& positions, std::vector<Vec3>& normals,
               const std::string& path);

}  // namespace bounce
