// Loading a scene: a JSON scene file (docs/scene-format.md) or a bare glTF 2.0 file with its
// camera and punctual lights. Bad input raises InputError naming the file and the JSON
// pointer (or line:column) of the problem. Camera and render settings are read through the
// parameter table (params.h); JSON parsing and overrides are json_reader.h's, mesh files
// mesh_import.h's.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "bounce/scene/json_reader.h"
#include "bounce/scene/load_resources.h"
#include "bounce/scene/scene.h"

namespace bounce {

/// How a scene is loaded: at which frame of its shot.
struct LoadOptions {
    std::optional<double> frame;  ///< the time keyed values are taken at; default: the shot's first frame
    std::string frame_origin;     ///< how the user asked for it ("--frame 60"), for errors
    /// Called with every file and folder the scene names (resolved path, JSON pointer) before
    /// it is read or used; throws to refuse it (the lighting tool confines its edits). Null: none.
    std::function<void(const std::string& path, const std::string& pointer)> check_path;
    LoadResources resources;  ///< where parsed meshes and embedded images are kept
};

/// Loads `path` (.json, or .gltf/.glb/.obj/.ply rendered with defaults and the file's own
/// camera and lights) and applies `overrides`, each "dotted.path=value" where value is JSON
/// (a bare word is taken as a string): `camera.fov=45`, `lights.0.color=[1,1,1]`; then every
/// keyed value is taken at the frame (keyframes.h). A frame outside the shot is an error.
Scene load_scene(const std::string& path, const std::vector<Override>& overrides = {}, const LoadOptions& options = {});

/// Same, from JSON text already in memory; `path` names it in errors and anchors relative
/// file names.
Scene load_scene_text(const std::string& text, const std::string& path, const std::vector<Override>& overrides = {},
                      const LoadOptions& options = {});

}  // namespace bounce
