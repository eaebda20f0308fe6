// What an object's mesh file pulls in, for the readers of mesh objects (object_reader.cpp) and
// subdivision surfaces (subdivision_reader.cpp): the files it names, confined as the mesh itself
// and recorded as the scene's inputs; its parse, timed; and what its materials carry that is not
// read, named once per file.
#pragma once

#include <chrono>
#include <string>

#include "bounce/scene/json_reader.h"
#include "bounce/scene/mesh_import.h"
#include "bounce/scene/scene.h"

namespace bounce {

/// What a mesh file named by `key` pulls in is confined as the mesh itself (check_path).
MeshInputs mesh_inputs(const JsonReader& r, const std::string& key);

/// Files a mesh file pulled in, recorded as inputs under the key that named the mesh.
void record_inputs(const JsonReader& r, const std::string& key, const MeshInputs& read);

/// Runs `parse` (a mesh file's load), its time counted in the scene's mesh_parse_seconds.
template <class Parse>
inline void parsing_mesh(Scene& scene, Parse&& parse) {
    const auto start = std::chrono::steady_clock::now();
    parse();
    scene.load_times.mesh_parse_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// What `file`'s own materials (read for object `object`) carry that is not read
/// (material_report.h): on each of its materials, and named once per file on the scene.
void note_unread(Scene& scene, const std::string& file, int mat, const std::string& object);

/// "<file>: ignored: <what>" on the scene's unread lines, once.
void note_ignored(Scene& scene, const std::string& file, const std::string& what);

}  // namespace bounce
