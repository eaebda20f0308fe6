// Readers of a scene file's items other than objects: lights (keys checked per light type),
// materials, object transforms. Each names the JSON pointer of a bad value.
#pragma once

#include <string>
#include <vector>

#include "bounce/scene/json_reader.h"
#include "bounce/scene/scene.h"

namespace bounce {

/// The keys a material may have.
const std::vector<std::string>& material_keys();
/// The material keys that change only how a surface reflects light to the camera, not the
/// light that bounces (Scene::fingerprint leaves them out; the lighting tool's stale state).
const std::vector<std::string>& surface_shading_keys();
/// Every key any light type reads (the reader then checks them against the light's type).
const std::vector<std::string>& light_keys();

/// The numeric keys a light of `type` reads and their defaults ({"intensity": 1, ...}; what the
/// reader uses, for the lighting tool's rows of keys a scene leaves out). Empty for an unknown type.
nlohmann::json light_defaults(const std::string& type);
/// The numeric keys of a material and their defaults.
nlohmann::json material_defaults();

Material read_material(const JsonReader& m, const std::string& name);
Light read_light(const JsonReader& r);
/// An object's "transform": {translate, rotate [deg, axis], scale} or {matrix}; identity if absent.
Transform read_transform(const JsonReader& obj);
/// The same read from the transform's own keys (`t` allows translate, rotate, scale, matrix).
Transform read_transform_keys(const JsonReader& t);

}  // namespace bounce
