#include "bounce/scene/material_report.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "bounce/core/files.h"
#include "bounce/scene/gltf_materials.h"
#include "bounce/scene/mesh_checks.h"

namespace bounce {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

/// Counts of what is not read, by feature, in the order first seen.
class Tally {
  public:
    /// `material`: the file's name of the material that carries it (none for other units).
    void add(const std::string& what, const std::string& unit, const std::string& material = "") {
        auto [it, fresh] = index_.emplace(what, out_.size());
        if (fresh) out_.push_back({what, 0, unit, {}});
        UnreadFeature& f = out_[it->second];
        if (!material.empty() && std::find(f.materials.begin(), f.materials.end(), material) != f.materials.end()) return;
        ++f.count;
        if (!material.empty()) f.materials.push_back(material);
    }
    std::vector<UnreadFeature> take() { return std::move(out_); }

  private:
    std::map<std::string, size_t> index_;
    std::vector<UnreadFeature> out_;
};

// Top-level extensions bounce (or Assimp for it) reads; material ones are named per material
// (gltf_materials.h).
const std::set<std::string> kGltfReadFileExtensions = {"KHR_lights_punctual",
                                                       "EXT_mesh_gpu_instancing",
                                                       "KHR_materials_emissive_strength",
                                                       "KHR_mesh_quantization",
                                                       "KHR_texture_transform",
                                                       "KHR_materials_transmission",
                                                       "KHR_materials_ior",
                                                       "KHR_materials_diffuse_transmission"};

std::vector<UnreadFeature> gltf_unread(const std::string& path) {
    const json j = json::parse(gltf_json_text(path), nullptr, false);
    Tally tally;
    if (!j.is_object()) return {};
    const std::vector<GltfMaterialJson> materials = read_gltf_materials(j, path);
    if (j.contains("materials") && j["materials"].is_array())
        for (size_t i = 0; i < j["materials"].size(); ++i) {
            const json& m = j["materials"][i];
            const std::string name = m.is_object() && m.contains("name") && m["name"].is_string() && !m["name"].get<std::string>().empty()
                                         ? m["name"].get<std::string>()
                                         : std::to_string(i);
            if (i < materials.size())
                for (const std::string& what : materials[i].unread) tally.add(what, "material", name);
        }
    if (j.contains("samplers") && j["samplers"].is_array())
        for (const json& s : j["samplers"])
            if (s.is_object() && (s.value("wrapS", 10497) != 10497 || s.value("wrapT", 10497) != 10497))
                tally.add("sampler wrap modes other than REPEAT (textures repeat)", "sampler");
    // Extensions the file uses that were not named above per material (KHR_materials_variants, ...).
    std::vector<UnreadFeature> out = tally.take();
    if (j.contains("extensionsUsed") && j["extensionsUsed"].is_array())
        for (const json& e : j["extensionsUsed"]) {
            if (!e.is_string() || kGltfReadFileExtensions.count(e.get<std::string>())) continue;
            const std::string name = e.get<std::string>().substr(0, 80);
            if (std::none_of(out.begin(), out.end(), [&](const UnreadFeature& f) { return f.what == name; }))
                out.push_back({name, 1, "file", {}});
        }
    return out;
}

// MTL statements mesh_import reads (through Assimp), and those that mean nothing to a renderer
// of light (ambient colour and the legacy illumination model number).
const std::set<std::string> kMtlRead = {"newmtl",   "Kd",       "map_Kd", "Ks", "Ns",    "Ke", "bump",
                                        "map_bump", "map_Bump", "d",      "Tr", "map_d", "Ka", "illum"};

/// One MTL material's statements not read. Ni (the index of refraction) matters only to a
/// transparent material (d < 1, Tr > 0, or an illumination model of refraction): the Cornell
/// box's walls carry Ni 1.5 with illum 2, meaning nothing.
struct MtlMaterial {
    std::string name;
    std::set<std::string> keys;
    int illum = 2;
    float d = 1, tr = 0;
    void end(Tally& tally) {
        const bool transparent = d < 1 || tr > 0 || illum == 4 || illum == 6 || illum == 7 || illum == 9;
        for (const std::string& k : keys)
            if (k != "Ni" || transparent) tally.add("MTL " + k, "material", name.empty() ? "?" : name);
        *this = {};
    }
};

std::vector<UnreadFeature> obj_unread(const std::string& path) {
    Tally tally;
    std::ifstream obj(path, std::ios::binary);
    for (std::string line; std::getline(obj, line);) {
        if (line.rfind("mtllib", 0) != 0) continue;
        std::istringstream names(line.substr(6));
        for (std::string name; names >> name;) {
            const fs::path mtl = (fs::path(path).parent_path() / name).lexically_normal();
            if (!not_a_regular_file(mtl.string()).empty()) continue;
            std::ifstream in(mtl, std::ios::binary);
            MtlMaterial m;  // each statement counted once per material
            for (std::string l; std::getline(in, l);) {
                std::istringstream words(l);
                std::string key;
                if (!(words >> key) || key[0] == '#') continue;
                if (key == "newmtl") {
                    m.end(tally);
                    std::getline(words >> std::ws, m.name);
                    while (!m.name.empty() && std::isspace(static_cast<unsigned char>(m.name.back()))) m.name.pop_back();
                }
                if (key == "illum") words >> m.illum;
                if ((key == "d" && words >> m.d) || (key == "Tr" && words >> m.tr)) continue;
                if (!kMtlRead.count(key)) m.keys.insert(key.substr(0, 40));
            }
            m.end(tally);
        }
    }
    return tally.take();
}

}  // namespace

std::string UnreadFeature::line() const { return fmt::format("{} on {} {}{}", what, count, unit, count == 1 ? "" : "s"); }

std::vector<UnreadFeature> unread_material_features(const std::string& path) {
    const std::string ext = lower_extension(path);
    if (is_gltf_file(path)) return gltf_unread(path);
    if (ext == ".obj") return obj_unread(path);
    return {};
}

}  // namespace bounce
