#include "bounce/scene/gltf_materials.h"

#include <fmt/format.h>

#include <nlohmann/json.hpp>
#include <set>

#include "bounce/core/error.h"
#include "bounce/scene/mesh_checks.h"
#include "bounce/scene/surface_textures.h"

namespace bounce {

using nlohmann::json;

namespace {

// Material extensions read here (the rest are named as unread).
const std::set<std::string> kReadExtensions = {"KHR_materials_emissive_strength", "KHR_materials_transmission", "KHR_materials_ior",
                                               "KHR_materials_diffuse_transmission"};

/// One material's reading, its values checked where they are (a JSON pointer each).
class MaterialJson {
  public:
    explicit MaterialJson(const std::string& path) : path_(path) {}

    /// A number at `key` of `j` inside [lo, hi] (`def` when absent).
    float number(const json& j, const char* key, float def, double lo, double hi, const std::string& where) const {
        if (!j.is_object() || !j.contains(key)) return def;
        const json& v = j[key];
        if (!v.is_number() || !(v.get<double>() >= lo && v.get<double>() <= hi))
            throw InputError(path_, where + "/" + key, fmt::format("{} is not a number in [{:g}, {:g}]", v.dump().substr(0, 40), lo, hi));
        return v.get<float>();
    }

    /// A textureInfo (`slot`: "occlusionTexture", ...): its uv set and transform; the first one
    /// seen is the material's, and a texture that differs from it is not read, and named.
    void texture(const json& t, const char* slot, const std::string& where, GltfMaterialJson& out) {
        if (!t.is_object()) return;
        uint8_t set = static_cast<uint8_t>(number(t, "texCoord", 0, 0, 1, where));
        UvTransform xf;
        const json* ext = t.contains("extensions") && t["extensions"].is_object() && t["extensions"].contains("KHR_texture_transform")
                              ? &t["extensions"]["KHR_texture_transform"]
                              : nullptr;
        if (ext) {
            const std::string at = where + "/extensions/KHR_texture_transform";
            const auto pair = [&](const char* k, Vec2 def) {
                if (!ext->is_object() || !ext->contains(k)) return def;
                const json& v = (*ext)[k];
                if (!v.is_array() || v.size() != 2) throw InputError(path_, at + "/" + k, "expected two numbers");
                return Vec2{number(v, 0, at + "/" + k), number(v, 1, at + "/" + k)};
            };
            std::string why;
            if (!make_uv_transform(pair("offset", xf.offset), number(*ext, "rotation", 0, -1e6, 1e6, at), pair("scale", xf.scale), xf, why))
                throw InputError(path_, at, why);
            set = static_cast<uint8_t>(number(*ext, "texCoord", set, 0, 1, at));
        }
        if (!seen_) {
            seen_ = true, out.uv_transform = xf, out.uv_set = set;
            return;
        }
        if (set == out.uv_set && xf == out.uv_transform) return;
        out.skipped.emplace_back(slot);
        note(out, fmt::format("{} on another uv set or transform than the material's first texture", slot));
    }

    void note(GltfMaterialJson& out, std::string what) const {
        for (const std::string& u : out.unread)
            if (u == what) return;
        out.unread.push_back(std::move(what));
    }

    /// Element i of a JSON array, a number inside [lo, hi].
    float number(const json& array, size_t i, const std::string& where, double lo = -1e6, double hi = 1e6) const {
        const json& v = array[i];
        if (!v.is_number() || !(v.get<double>() >= lo && v.get<double>() <= hi))
            throw InputError(path_, fmt::format("{}/{}", where, i),
                             fmt::format("{} is not a number in [{:g}, {:g}]", v.dump().substr(0, 40), lo, hi));
        return v.get<float>();
    }
    const std::string& path() const { return path_; }

  private:
    const std::string& path_;
    bool seen_ = false;
};

/// KHR_materials_diffuse_transmission's factor and colour (its textures are named, not read).
void read_diffuse_transmission(const MaterialJson& r, const json& d, const std::string& e, GltfMaterialJson& out) {
    const std::string at = e + "KHR_materials_diffuse_transmission";
    out.diffuse_transmission = r.number(d, "diffuseTransmissionFactor", 0, 0, 1, at);
    if (d.is_object() && d.contains("diffuseTransmissionColorFactor")) {
        const json& c = d["diffuseTransmissionColorFactor"];
        if (!c.is_array() || c.size() != 3) throw InputError(r.path(), at + "/diffuseTransmissionColorFactor", "expected three numbers");
        for (size_t i = 0; i < 3; ++i)
            out.diffuse_transmission_color[static_cast<int>(i)] = r.number(c, i, at + "/diffuseTransmissionColorFactor", 0, 1);
    }
    for (const char* t : {"diffuseTransmissionTexture", "diffuseTransmissionColorTexture"})
        if (d.is_object() && d.contains(t)) r.note(out, std::string("KHR_materials_diffuse_transmission.") + t);
}

GltfMaterialJson read_material(const json& m, const std::string& path, const std::string& at) {
    GltfMaterialJson out;
    if (!m.is_object()) return out;
    MaterialJson r(path);
    // The base colour's texture first: its transform is the material's.
    const json pbr = m.value("pbrMetallicRoughness", json::object());
    for (const char* t : {"baseColorTexture", "metallicRoughnessTexture"})
        if (pbr.is_object() && pbr.contains(t)) r.texture(pbr[t], t, at + "/pbrMetallicRoughness/" + t, out);
    for (const char* t : {"emissiveTexture", "occlusionTexture", "normalTexture"})
        if (m.contains(t)) r.texture(m[t], t, at + "/" + t, out);
    if (m.contains("occlusionTexture") && m["occlusionTexture"].is_object() && m["occlusionTexture"].value("strength", 1.0) != 1.0)
        r.note(out, "occlusionTexture.strength");
    const json ext = m.value("extensions", json::object());
    if (!ext.is_object()) return out;
    const std::string e = at + "/extensions/";
    if (ext.contains("KHR_materials_emissive_strength"))
        out.emissive_strength = r.number(ext["KHR_materials_emissive_strength"], "emissiveStrength", 1, 0, kMaxRadiometric,
                                         e + "KHR_materials_emissive_strength");
    if (ext.contains("KHR_materials_transmission")) {
        const json& t = ext["KHR_materials_transmission"];
        out.transmission = r.number(t, "transmissionFactor", 0, 0, 1, e + "KHR_materials_transmission");
        if (t.is_object() && t.contains("transmissionTexture")) r.note(out, "KHR_materials_transmission.transmissionTexture");
    }
    if (ext.contains("KHR_materials_diffuse_transmission")) read_diffuse_transmission(r, ext["KHR_materials_diffuse_transmission"], e, out);
    // Real dielectrics lie in [1, 3], as the scene file's ior.
    if (ext.contains("KHR_materials_ior")) out.ior = r.number(ext["KHR_materials_ior"], "ior", 1.5f, 1, 3, e + "KHR_materials_ior");
    for (const auto& [name, value] : ext.items())
        if (!kReadExtensions.count(name)) r.note(out, name.substr(0, 80));
    return out;
}

}  // namespace

std::vector<GltfMaterialJson> read_gltf_materials(const std::string& path) {
    if (!is_gltf_file(path)) return {};
    return read_gltf_materials(json::parse(gltf_json_text(path), nullptr, false), path);  // check_mesh_file parsed it
}

std::vector<GltfMaterialJson> read_gltf_materials(const nlohmann::json& j, const std::string& path) {
    std::vector<GltfMaterialJson> out;
    if (!j.is_object() || !j.contains("materials") || !j["materials"].is_array()) return out;
    for (size_t i = 0; i < j["materials"].size(); ++i)
        out.push_back(read_material(j["materials"][i], path, fmt::format("/materials/{}", i)));
    return out;
}

}  // namespace bounce
