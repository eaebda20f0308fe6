#include "bounce/scene/mesh_materials.h"

#include <assimp/GltfMaterial.h>
#include <assimp/material.h>
#include <assimp/scene.h>
#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "bounce/core/error.h"
#include "bounce/core/files.h"
#include "bounce/core/image.h"
#include "bounce/scene/embedded_images.h"
#include "bounce/scene/gltf_materials.h"
#include "bounce/scene/mesh_checks.h"
#include "bounce/scene/opacity.h"
#include "bounce/scene/surface_textures.h"

namespace bounce {

namespace fs = std::filesystem;

namespace {

Vec3 to_vec3(const aiColor3D& v) { return {v.r, v.g, v.b}; }

/// A file material's cutout: glTF's alphaMode, alphaCutoff and base colour alpha (factor times
/// the base colour texture's alpha, if it has one); MTL's d (or 1 - Tr) and map_d, as blend,
/// as Blender's importer reads them. `map_d`: the OPACITY texture's path (empty: none).
void read_file_cutout(const aiMaterial& am, const std::string& path, const std::string& where, const std::string& map_d, Material& m) {
    std::string why;
    aiString mode;
    if (am.Get(AI_MATKEY_GLTF_ALPHAMODE, mode) == AI_SUCCESS) {
        const std::string name = mode.C_Str();
        if (name == "OPAQUE") return;
        if (name != "MASK" && name != "BLEND")
            throw InputError(path, where, fmt::format("alphaMode \"{}\" is not OPAQUE, MASK or BLEND", name.substr(0, 40)));
        m.alpha_mode = name == "MASK" ? AlphaMode::Mask : AlphaMode::Blend;
        aiColor4D base{1, 1, 1, 1};
        am.Get(AI_MATKEY_BASE_COLOR, base);
        m.opacity = base.a;
        if (m.alpha_mode == AlphaMode::Mask) am.Get(AI_MATKEY_GLTF_ALPHACUTOFF, m.alpha_cutoff);
        if (!m.color_texture.empty()) {
            m.opacity_map = load_opacity_map(m.color_texture, OpacityChannel::AlphaOnly, why);
            if (m.opacity_map) m.opacity_texture = m.color_texture;
        }
    } else {
        float d = 1;
        am.Get(AI_MATKEY_OPACITY, d);
        if (d >= 1 && map_d.empty()) return;
        m.alpha_mode = AlphaMode::Blend;
        m.opacity = d;
        if (!map_d.empty()) {
            m.opacity_texture = map_d;
            m.opacity_map = load_opacity_map(map_d, OpacityChannel::AlphaOrFirst, why);
        }
    }
    if (!why.empty())
        throw InputError(path, where,
                         fmt::format("opacity texture \"{}\": {}", m.opacity_texture.empty() ? m.color_texture : m.opacity_texture, why));
    if (!(m.opacity >= 0 && m.opacity <= 1)) throw InputError(path, where, fmt::format("opacity {} is not in [0, 1]", m.opacity));
    if (!(m.alpha_cutoff >= 0 && m.alpha_cutoff <= 1))
        throw InputError(path, where, fmt::format("alphaCutoff {} is not in [0, 1]", m.alpha_cutoff));
}

/// A file material's texture of the first of `types` it has ("" when none): an image embedded in
/// the file, written out (bounce's own: recorded, not confined), or a file beside the mesh file
/// (confined through `files_read` before anything opens it). It must be there: a missing one
/// would render untextured.
std::string file_texture(const aiScene& s, const aiMaterial& am, std::initializer_list<aiTextureType> types, const std::string& path,
                         const std::string& where, MeshInputs* files_read) {
    aiString tex;
    for (aiTextureType type : types) {
        if (am.GetTexture(type, 0, &tex) != AI_SUCCESS) continue;
        std::string t;
        if (const aiTexture* embedded = s.GetEmbeddedTexture(tex.C_Str())) {
            t = embedded_image_file(*embedded, files_read ? files_read->resources.images : std::string(), path, where);
            if (files_read) files_read->files.push_back(t);
        } else {
            t = (fs::path(path).parent_path() / tex.C_Str()).lexically_normal().string();
            if (files_read) files_read->add(t);
        }
        std::string why = not_a_regular_file(t);
        if (why.empty()) why = texture_problem(t);
        if (!why.empty()) throw InputError(path, where, fmt::format("texture \"{}\": {}", t, why));
        return t;
    }
    return "";
}

/// What a glTF material adds to Assimp's reading: its occlusion, emission and metallic-roughness
/// textures, where its textures are read, and KHR_materials_transmission onto bounce's glass
/// (the base colour tints what is let through, as Cycles' Principled BSDF does).
template <class Texture>
void read_gltf_parts(const GltfMaterialJson& g, const Texture& texture, const std::string& path, const std::string& where, Material& m) {
    const auto read = [&](const char* slot) { return std::find(g.skipped.begin(), g.skipped.end(), slot) == g.skipped.end(); };
    // occlusionTexture (its red channel) is baked occlusion, as ao_texture.
    if (read("occlusionTexture")) m.ao_texture = texture({aiTextureType_LIGHTMAP, aiTextureType_AMBIENT_OCCLUSION});
    if (read("metallicRoughnessTexture")) m.metallic_roughness_texture = texture({aiTextureType_UNKNOWN});
    if (read("emissiveTexture")) m.emission_texture = texture({aiTextureType_EMISSIVE});
    if (!read("normalTexture")) m.normal_texture.clear();
    if (!m.emission_texture.empty()) {
        std::string why;
        m.emission_map = load_emission_map(m.emission_texture, why);
        if (!m.emission_map) throw InputError(path, where, fmt::format("emissive texture \"{}\": {}", m.emission_texture, why));
    }
    m.uv_transform = g.uv_transform;
    m.uv_set = g.uv_set;
    if (g.transmission && *g.transmission > 0) {
        m.transmission = m.color * *g.transmission, m.ior = g.ior;
        return;  // KHR_materials_diffuse_transmission: "the transmission effect overrides" it
    }
    m.diffuse_transmission = g.diffuse_transmission, m.diffuse_transmission_color = g.diffuse_transmission_color;
}

}  // namespace

/// The file's materials appended to `materials` (named "<prefix>/<name>"), or `override_material`
/// for all: the scene index of each of the file's materials.
std::vector<uint32_t> import_materials(const aiScene* s, const std::string& path, const std::string& prefix,
                                       std::vector<Material>& materials, int override_material, MeshInputs* files_read) {
    std::vector<uint32_t> mat_map(s->mNumMaterials);
    if (override_material < 0) {
        const std::vector<GltfMaterialJson> gltf = read_gltf_materials(path);
        for (unsigned i = 0; i < s->mNumMaterials; ++i) {
            const aiMaterial* am = s->mMaterials[i];
            Material m;
            aiString name;
            am->Get(AI_MATKEY_NAME, name);
            m.name = prefix + "/" + (name.length ? name.C_Str() : std::to_string(i));
            aiColor4D base;
            aiColor3D diffuse;
            if (am->Get(AI_MATKEY_BASE_COLOR, base) == AI_SUCCESS)
                m.color = {base.r, base.g, base.b};
            else if (am->Get(AI_MATKEY_COLOR_DIFFUSE, diffuse) == AI_SUCCESS)
                m.color = to_vec3(diffuse);
            const std::string where = "material " + m.name.substr(prefix.size() + 1);
            // As a JSON material's: an albedo above 1 creates energy, a radiance above 1e20 overflows.
            for (int c = 0; c < 3; ++c)
                if (!(m.color[c] >= 0 && m.color[c] <= 1))
                    throw InputError(path, where, fmt::format("base colour {} is not in [0, 1]", m.color[c]));
            aiColor3D ke;
            if (am->Get(AI_MATKEY_COLOR_EMISSIVE, ke) == AI_SUCCESS) m.emission = to_vec3(ke);
            float strength = 1;
            if (am->Get(AI_MATKEY_EMISSIVE_INTENSITY, strength) == AI_SUCCESS)
                m.emission = m.emission * strength;
            else if (i < gltf.size())
                m.emission = m.emission * gltf[i].emissive_strength;
            for (int c = 0; c < 3; ++c)
                if (!(m.emission[c] >= 0 && m.emission[c] <= kMaxRadiometric))
                    throw InputError(path, where, fmt::format("emission {} is not in [0, {:g}]", m.emission[c], kMaxRadiometric));
            // Glossy lobe: glTF metallic-roughness (F0 = mix(0.04, base, metallic), the diffuse
            // part darkened by 1 - metallic), or MTL's Ks and Ns (Blinn-Phong exponent to GGX
            // roughness: alpha = sqrt(2 / (Ns + 2))).
            float metallic = 0, rough = 1, ns = 0;
            aiColor3D ks;
            if (am->Get(AI_MATKEY_ROUGHNESS_FACTOR, rough) == AI_SUCCESS) {
                am->Get(AI_MATKEY_METALLIC_FACTOR, metallic);
                metallic = std::clamp(metallic, 0.0f, 1.0f);
                m.specular = Color(0.04f) * (1 - metallic) + m.color * metallic;
                m.metallic = metallic;
                m.roughness = std::clamp(rough, 0.01f, 1.0f);
            } else if (am->Get(AI_MATKEY_COLOR_SPECULAR, ks) == AI_SUCCESS && (ks.r > 0 || ks.g > 0 || ks.b > 0)) {
                m.specular = vmin(vmax(to_vec3(ks), Color(0)), Color(1));
                if (am->Get(AI_MATKEY_SHININESS, ns) == AI_SUCCESS && ns > 0)
                    m.roughness = std::clamp(std::sqrt(std::sqrt(2 / (ns + 2))), 0.01f, 1.0f);
            }
            const auto texture = [&](std::initializer_list<aiTextureType> types) {
                return file_texture(*s, *am, types, path, where, files_read);
            };
            m.color_texture = texture({aiTextureType_BASE_COLOR, aiTextureType_DIFFUSE});
            // glTF's base colour factor multiplies its texture; an MTL's map_Kd replaces Kd, as
            // Blender's importer (and so Cycles) reads it.
            if (!m.color_texture.empty() && gltf.empty()) m.color = Color(1);
            read_file_cutout(*am, path, where, texture({aiTextureType_OPACITY}), m);
            // Assimp files MTL's bump maps under HEIGHT, glTF's normalTexture under NORMALS.
            m.bump_texture = texture({aiTextureType_HEIGHT, aiTextureType_DISPLACEMENT});
            m.normal_texture = texture({aiTextureType_NORMALS});
            if (i < gltf.size()) read_gltf_parts(gltf[i], texture, path, where, m);
            // Without a metallic-roughness texture the metalness is one number: the albedo is
            // darkened here (with one, per texel where it is read: Materials).
            if (m.metallic_roughness_texture.empty()) m.color = m.color * (1 - metallic);
            mat_map[i] = static_cast<uint32_t>(materials.size());
            materials.push_back(m);
        }
    } else {
        mat_map.assign(s->mNumMaterials, static_cast<uint32_t>(override_material));
    }
    return mat_map;
}

}  // namespace bounce
