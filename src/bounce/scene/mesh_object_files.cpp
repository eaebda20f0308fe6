#include "bounce/scene/mesh_object_files.h"

#include <algorithm>

#include "bounce/scene/material_report.h"

namespace bounce {

MeshInputs mesh_inputs(const JsonReader& r, const std::string& key) {
    MeshInputs in;
    in.resources = r.ctx().resources;
    if (r.ctx().check_path) in.check = [check = r.ctx().check_path, at = r.at(key)](const std::string& f) { check(f, at); };
    return in;
}

void record_inputs(const JsonReader& r, const std::string& key, const MeshInputs& read) {
    if (r.ctx().inputs)
        for (const std::string& f : read.files) r.ctx().inputs->push_back({f, r.at(key)});
}

void note_unread(Scene& scene, const std::string& file, int mat, const std::string& object) {
    if (mat >= 0) return;  // a scene material replaces the file's
    const std::vector<UnreadFeature> unread = unread_material_features(file);
    for (const UnreadFeature& f : unread)
        for (const std::string& name : f.materials)
            for (Material& m : scene.materials)
                if (m.name == object + "/" + name) m.unread.push_back(f.what);
    for (const UnreadFeature& f : unread) note_ignored(scene, file, f.line());
}

void note_ignored(Scene& scene, const std::string& file, const std::string& what) {
    const std::string line = file + ": ignored: " + what;
    if (std::find(scene.unread.begin(), scene.unread.end(), line) == scene.unread.end()) scene.unread.push_back(line);
}

}  // namespace bounce
