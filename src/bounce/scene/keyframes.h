// Time in scenes (docs/animation.md). A scene file's "animation" block gives the shot
// ({"fps": 24, "frames": [1, 48]}); any animatable value may be keyed in place of its value:
//   "position": {"keys": [[1, [0, 1, 5]], [48, [2, 1, 5]]], "interpolation": "smooth"}
// with "linear" (default), "smooth" (a C1 Catmull-Rom spline through the keys) or "step";
// an object's transform "rotate" [degrees, axis] is interpolated as a quaternion. Keys are in
// frames (fractions allowed). evaluate_keys turns a scene description into the plain one at a
// time, which the ordinary readers then check and build; which keys may be animated is the
// parameter table's `animatable` column (params.h).
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "bounce/scene/json_reader.h"
#include "bounce/scene/shot.h"

namespace bounce {

/// Reads the "animation" block (InputError at its pointer when malformed); a file with keyed
/// values but no block is an error too (its frames would be unknown).
ShotSettings read_shot(const nlohmann::json& doc, const JsonContext& ctx);

/// True when `doc` holds keyed values anywhere.
bool has_keys(const nlohmann::json& doc);
/// True when a scene's keyed values (Scene::keyed) key a light or a material's emission.
bool keys_light(const nlohmann::json& keyed);

/// `doc` with every keyed value replaced by its value at `frame`. InputError (with the pointer
/// of the key) for keys out of order or repeated, values that are not finite numbers or change
/// shape between keys, an unknown interpolation, and keys on a value that cannot be animated.
nlohmann::json evaluate_keys(const nlohmann::json& doc, double frame, const JsonContext& ctx);

}  // namespace bounce
