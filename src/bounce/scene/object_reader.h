// Reading a scene file's objects: meshes (optionally subdivision surfaces, diced from the
// camera, with displacement), quads and spheres, their transforms and fur. Keys are checked per
// object type: a key another type reads (a "displacement" on a sphere, "boundary" without
// "subdivision") is an error, never ignored. Every file an object reads is recorded in the
// scene's inputs.
#pragma once

#include <string>
#include <vector>

#include "bounce/scene/json_reader.h"
#include "bounce/scene/scene.h"

namespace bounce {

/// Every key any object type reads.
const std::vector<std::string>& object_keys();

/// Appends object number `index` (read from `r`) to `scene.objects`. A still mesh file whose
/// nodes share meshes (glTF) places them as instances: those go to `later` (appended after the
/// scene file's entries, which keep their indices), unless the file has nothing else, when the
/// first takes the object's place.
void read_object(const JsonReader& r, Scene& scene, const DicingSettings& dicing, size_t index, std::vector<Object>& later);

/// Before any object is read: the triangles the scene's spheres will be tessellated into (both
/// levels), against render.memory_budget and free memory, with the estimate (100 000 spheres
/// ran for minutes into 14 GB before the camera was found to see none of them).
void check_generated_geometry(const JsonReader& root, const nlohmann::json& objects, const DicingSettings& dicing);

/// The visible mesh of mesh object `r` (one that plays its file's animation) posed at `frame`
/// and placed by `r`'s transform: a deforming mesh at shutter open and close (motion blur), and
/// where its fur is groomed.
TriangleMesh posed_visible_mesh(const JsonReader& r, const Scene& scene, double frame);

/// Index of the material named `name`, or -1.
int material_index(const Scene& scene, const std::string& name);
/// The material `r` names under `key` (-1: no such key); an unknown name fails with the closest one.
int read_material_name(const JsonReader& r, const std::string& key, const Scene& scene);

}  // namespace bounce
