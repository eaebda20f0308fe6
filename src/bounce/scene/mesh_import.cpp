#include "bounce/scene/mesh_import.h"

#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <fmt/format.h>

#include <assimp/Importer.hpp>
#include <array>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <optional>
#include <sstream>

#include "bounce/core/error.h"
#include "bounce/core/files.h"
#include "bounce/core/image.h"
#include "bounce/scene/embedded_images.h"
#include "bounce/scene/gltf_instances.h"
#include "bounce/scene/mesh_cache.h"
#include "bounce/scene/mesh_animation.h"
#include "bounce/scene/mesh_checks.h"
#include "bounce/scene/mesh_materials.h"

namespace bounce {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

Vec3 to_vec3(const aiVector3D& v) { return {v.x, v.y, v.z}; }
Vec3 to_vec3(const aiColor3D& v) { return {v.r, v.g, v.b}; }

Transform to_transform(const aiMatrix4x4& a) {
    Transform t;
    const float* src = &a.a1;
    for (int i = 0; i < 16; ++i) t.m[static_cast<size_t>(i)] = src[i];
    return t;
}

aiMatrix4x4 to_ai(const Transform& t) {
    const auto& m = t.m;
    return {m[0], m[1], m[2], m[3], m[4], m[5], m[6], m[7], m[8], m[9], m[10], m[11], m[12], m[13], m[14], m[15]};
}

aiMatrix4x4 node_world(const aiNode* n) {
    aiMatrix4x4 m;
    for (; n; n = n->mParent) m = n->mTransformation * m;
    return m;
}

const unsigned kAssimpFlags =
    aiProcess_Triangulate | aiProcess_JoinIdenticalVertices | aiProcess_SortByPType | aiProcess_ValidateDataStructure;

/// Reads `path` through Assimp after mesh_checks.h's checks; the files it names (a glTF's
/// buffers and images, an OBJ's MTL files) pass `files_read` before Assimp opens them.
const aiScene* import_file(Assimp::Importer& imp, const std::string& path, unsigned flags, MeshInputs* files_read, bool own_materials) {
    imp.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
    MeshCheckOptions checks;
    checks.own_materials = own_materials;
    if (files_read && files_read->check) checks.before_open = files_read->check;
    const std::vector<std::string> named = check_mesh_file(path, checks);
    if (files_read)
        for (const std::string& f : named) files_read->add(f);
    const aiScene* s = imp.ReadFile(path, flags);
    if (!s) throw InputError(path, "", std::string("cannot load mesh: ") + imp.GetErrorString());
    return s;
}

/// Calls fn(mesh, world transform) for every mesh instance of the node tree.
template <typename Fn>
void for_each_mesh_instance(const aiScene* s, Fn&& fn) {
    std::vector<std::pair<const aiNode*, aiMatrix4x4>> stack{{s->mRootNode, s->mRootNode->mTransformation}};
    while (!stack.empty()) {
        auto [node, world] = stack.back();
        stack.pop_back();
        for (unsigned c = 0; c < node->mNumChildren; ++c)
            stack.emplace_back(node->mChildren[c], world * node->mChildren[c]->mTransformation);
        const Transform t = to_transform(world);
        for (unsigned k = 0; k < node->mNumMeshes; ++k) fn(s->mMeshes[node->mMeshes[k]], t);
    }
}

/// Calls fn(node, mesh index) for every mesh a node of the tree uses.
template <typename Fn>
void for_each_node_mesh(const aiScene* s, Fn&& fn) {
    std::vector<const aiNode*> stack{s->mRootNode};
    while (!stack.empty()) {
        const aiNode* node = stack.back();
        stack.pop_back();
        for (unsigned c = 0; c < node->mNumChildren; ++c) stack.push_back(node->mChildren[c]);
        for (unsigned k = 0; k < node->mNumMeshes; ++k) fn(node, node->mMeshes[k]);
    }
}

/// Calls fn(mesh, posed world transform) for every mesh instance of the node tree.
template <typename Fn>
void for_each_posed_instance(const aiScene* s, const std::unordered_map<const aiNode*, aiMatrix4x4>& nodes, Fn&& fn) {
    for_each_node_mesh(s, [&](const aiNode* node, unsigned mesh) { fn(s->mMeshes[mesh], nodes.at(node)); });
}

/// Where `node` places its mesh `am`: at the node (its world transform `world`), or at each of
/// its GPU instances, in its space, named "<node>/<i>". GPU instances of a skinned or morphed
/// mesh are refused (the extension places rigid copies).
std::vector<MeshFileParts::Use> node_placements(const aiNode* node, const aiMesh* am, const aiMatrix4x4& world,
                                                const std::unordered_map<const aiNode*, GpuInstances>& gpu, const std::string& path) {
    // A placement that flattens its mesh is refused, as the scene file refuses one.
    const auto flat = [&](const Transform& t, const std::string& where) {
        if (t.flattens()) throw InputError(path, where, "the placement is singular (a zero scale or matrix flattens the object)");
        return t;
    };
    const auto it = gpu.find(node);
    if (it == gpu.end()) return {{node->mName.C_Str(), flat(to_transform(world), fmt::format("node \"{}\"", node->mName.C_Str()))}};
    if (am->HasBones() || am->mNumAnimMeshes > 0)
        throw InputError(path, it->second.pointer, "instances of a skinned or morphed mesh are not supported");
    std::vector<MeshFileParts::Use> at;
    for (size_t i = 0; i < it->second.at.size(); ++i)
        at.push_back({fmt::format("{}/{}", node->mName.C_Str(), i),
                      flat(to_transform(world) * it->second.at[i], fmt::format("{} instance {}", it->second.pointer, i))});
    return at;
}

/// The uv set the textures of material `mat` read on `am` (glTF's texCoord; the first set for
/// an object's own material, which may not be among `materials` yet): null when the mesh has
/// none; a second set the mesh lacks is refused, as glTF requires it.
const aiVector3D* uv_channel(const aiMesh* am, uint32_t mat, const std::vector<Material>& materials, const std::string& path) {
    const uint8_t set = mat < materials.size() ? materials[mat].uv_set : 0;
    if (set == 0 || am->mTextureCoords[set]) return am->mTextureCoords[set];
    throw InputError(path, fmt::format("mesh \"{}\"", am->mName.C_Str()),
                     fmt::format("material \"{}\" reads texCoord {}, a uv set the mesh does not have", materials[mat].name, set));
}

/// The triangles of `am` at `positions` and `normals` (posed), every face of material `mat`
/// (`materials[mat]`), with the uv set its textures read.
TriangleMesh triangles_of(const aiMesh* am, const std::vector<Vec3>& positions, const std::vector<Vec3>& normals, uint32_t mat,
                          const std::vector<Material>& materials, const std::string& path) {
    TriangleMesh m;
    const aiVector3D* uvs = uv_channel(am, mat, materials, path);
    // glTF's COLOR_0 multiplies the base colour (as Blender's importer wires it); an OBJ's or a
    // PLY's vertex colours are data that no material of theirs reads.
    const aiColor4D* colors = is_gltf_file(path) ? am->mColors[0] : nullptr;
    for (unsigned v = 0; v < am->mNumVertices; ++v) {
        m.positions.push_back(positions[v]);
        if (am->mNormals) m.normals.push_back(normals[v]);
        if (uvs) m.uvs.push_back({uvs[v].x, uvs[v].y});
        if (!colors) continue;
        const Color c{colors[v].r, colors[v].g, colors[v].b};
        for (int k = 0; k < 3; ++k)
            if (!(c[k] >= 0 && c[k] <= 1))
                throw InputError(path, fmt::format("mesh \"{}\" COLOR_0 vertex {}", am->mName.C_Str(), v),
                                 fmt::format("{} is not a colour component in [0, 1]", c[k]));
        m.colors.push_back(c);
    }
    for (unsigned f = 0; f < am->mNumFaces; ++f) {
        const aiFace& face = am->mFaces[f];
        if (face.mNumIndices != 3) continue;
        m.indices.insert(m.indices.end(), {face.mIndices[0], face.mIndices[1], face.mIndices[2]});
        m.face_materials.push_back(mat);
    }
    return m;
}

struct GltfCamera {
    float yfov = 0, aspect = 0;
};

/// The first perspective camera of a .gltf/.glb file, read from its JSON.
std::optional<GltfCamera> gltf_camera(const std::string& path) {
    if (!is_gltf_file(path)) return std::nullopt;
    const std::string ext = lower_extension(path);
    std::ifstream in(path, std::ios::binary);
    std::string text((std::istreambuf_iterator<char>(in)), {});
    if (ext == ".glb") {  // 12-byte header, then the JSON chunk: length, type, data
        if (text.size() < 20) return std::nullopt;
        uint32_t len = 0;
        std::memcpy(&len, text.data() + 12, 4);
        if (20 + static_cast<size_t>(len) > text.size()) return std::nullopt;
        text = text.substr(20, len);
    }
    json j = json::parse(text, nullptr, false);
    if (j.is_discarded() || !j.contains("cameras") || !j["cameras"].is_array() || j["cameras"].empty()) return std::nullopt;
    const json& c = j["cameras"][0];
    if (!c.contains("perspective") || !c["perspective"].contains("yfov")) return std::nullopt;
    const json& p = c["perspective"];
    GltfCamera g;
    g.yfov = p["yfov"].is_number() ? p["yfov"].get<float>() : 0;
    g.aspect = p.contains("aspectRatio") && p["aspectRatio"].is_number() ? p["aspectRatio"].get<float>() : 0;
    if (!(g.yfov > 0)) return std::nullopt;
    return g;
}

}  // namespace

json describe_mesh_file(const std::string& path) {
    Assimp::Importer imp;
    const aiScene* s = import_file(imp, path, kAssimpFlags, nullptr, true);
    json doc;
    doc["objects"] = json::array({{{"name", fs::path(path).stem().string()}, {"file", fs::path(path).filename().string()}}});
    if (s->mNumCameras == 0) throw InputError(path, "", "the file has no camera; write a JSON scene that names one (docs/scene-format.md)");
    const aiCamera* cam = s->mCameras[0];
    const aiNode* node = s->mRootNode->FindNode(cam->mName);
    Transform w = node ? to_transform(node_world(node)) : Transform{};
    float aspect = cam->mAspect > 0 ? cam->mAspect : 1.0f;
    Vec3 pos, look, up;
    float vfov;
    if (auto gltf = gltf_camera(path)) {
        // glTF: the camera looks down -Z of its node with +Y up. Assimp 5.2 also copies the
        // node translation into mPosition and stores yfov*aspect as the "horizontal" fov, so
        // take the pose from the node and the field of view from the file itself.
        pos = w.point(Vec3(0));
        look = w.vector({0, 0, -1});
        up = w.vector({0, 1, 0});
        vfov = gltf->yfov * 180.0f / kPi;
        if (gltf->aspect > 0) aspect = gltf->aspect;
    } else {
        pos = w.point(to_vec3(cam->mPosition));
        look = w.vector(to_vec3(cam->mLookAt));
        up = w.vector(to_vec3(cam->mUp));
        // Assimp documents mHorizontalFOV as half the horizontal angle.
        vfov = 2.0f * std::atan(std::tan(cam->mHorizontalFOV) / aspect) * 180.0f / kPi;
    }
    int width = 640, height = std::max(1, static_cast<int>(std::lround(640.0f / aspect)));
    doc["camera"] = {{"position", {pos.x, pos.y, pos.z}},
                     {"look_at", {pos.x + look.x, pos.y + look.y, pos.z + look.z}},
                     {"up", {up.x, up.y, up.z}},
                     {"fov", vfov},
                     {"resolution", {width, height}}};
    json lights = json::array();
    for (unsigned i = 0; i < s->mNumLights; ++i) {
        const aiLight* l = s->mLights[i];
        const aiNode* ln = s->mRootNode->FindNode(l->mName);
        Transform lw = ln ? to_transform(node_world(ln)) : Transform{};
        Vec3 p = lw.point(to_vec3(l->mPosition));
        Vec3 d = normalize(lw.vector(to_vec3(l->mDirection)));
        Vec3 c = to_vec3(l->mColorDiffuse);  // glTF: colour x intensity
        json jl = {{"color", {c.x, c.y, c.z}}};
        switch (l->mType) {
            case aiLightSource_POINT:
                jl["type"] = "point";
                jl["position"] = {p.x, p.y, p.z};
                break;
            case aiLightSource_SPOT: {
                jl["type"] = "spot";
                jl["position"] = {p.x, p.y, p.z};
                jl["direction"] = {d.x, d.y, d.z};
                float inner = l->mAngleInnerCone * 180.0f / kPi, outer = l->mAngleOuterCone * 180.0f / kPi;
                jl["cone_angle"] = std::min(inner, outer);
                jl["cone_falloff"] = std::max(0.0f, outer - inner);
                break;
            }
            case aiLightSource_DIRECTIONAL:
                jl["type"] = "distant";
                jl["direction"] = {d.x, d.y, d.z};
                break;
            default:
                continue;  // area/ambient lights of other formats are not punctual
        }
        lights.push_back(jl);
    }
    if (lights.empty()) lights.push_back({{"type", "sky"}, {"color", 1.0}});
    doc["lights"] = lights;
    return doc;
}

namespace {

TriangleMesh import_mesh_file(const std::string& path, const std::string& prefix, std::vector<Material>& materials, int override_material,
                              MeshInputs* files_read, const MeshPose& pose) {
    Assimp::Importer imp;
    const aiScene* s = import_file(imp, path, kAssimpFlags, files_read, override_material < 0);
    const std::vector<uint32_t> mat_map = import_materials(s, path, prefix, materials, override_material, files_read);
    // Posed (animation channels, skins, morph targets) or at rest.
    const MeshTime time{pose.clip.empty() ? -1 : find_clip(s, pose.clip, path), pose.seconds};
    const auto nodes = posed_nodes(s, time, path);
    const auto gpu = gltf_gpu_instances(path, s);
    TriangleMesh out;
    std::vector<Vec3> posed, posed_normals;
    for_each_node_mesh(s, [&](const aiNode* node, unsigned index) {
        const aiMesh* am = s->mMeshes[index];
        if (!(am->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) return;
        for (const MeshFileParts::Use& u : node_placements(node, am, nodes.at(node), gpu, path)) {  // (GPU instances flattened)
            pose_mesh(s, am, time, to_ai(u.world), nodes, posed, posed_normals, path);
            out.append(triangles_of(am, posed, posed_normals, mat_map[am->mMaterialIndex], materials, path));
        }
    });
    if (out.triangle_count() == 0) throw InputError(path, "", "mesh has no triangles");
    return out;
}

MeshFileParts import_mesh_parts(const std::string& path, const std::string& prefix, std::vector<Material>& materials, int override_material,
                                MeshInputs* files_read) {
    Assimp::Importer imp;
    const aiScene* s = import_file(imp, path, kAssimpFlags, files_read, override_material < 0);
    const std::vector<uint32_t> mat_map = import_materials(s, path, prefix, materials, override_material, files_read);
    const MeshTime rest;
    const auto nodes = posed_nodes(s, rest, path);
    const auto gpu = gltf_gpu_instances(path, s);
    std::vector<size_t> uses(s->mNumMeshes, 0);
    std::vector<int> slot(s->mNumMeshes, -1);
    for_each_node_mesh(s, [&](const aiNode* node, unsigned mesh) {
        const auto it = gpu.find(node);
        uses[mesh] += it == gpu.end() ? 1 : it->second.at.size();
    });
    MeshFileParts out;
    std::vector<Vec3> posed, posed_normals;
    for_each_node_mesh(s, [&](const aiNode* node, unsigned index) {
        const aiMesh* am = s->mMeshes[index];
        if (!(am->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) return;
        const uint32_t mat = mat_map[am->mMaterialIndex];
        const std::vector<MeshFileParts::Use> at = node_placements(node, am, nodes.at(node), gpu, path);
        // Shared: used more than once, rigid (no skin, no morph targets) and not a light (mesh
        // lights sample world triangles).
        if (uses[index] < 2 || am->HasBones() || am->mNumAnimMeshes > 0 || materials[mat].is_emissive()) {
            for (const MeshFileParts::Use& u : at) {
                pose_mesh(s, am, rest, to_ai(u.world), nodes, posed, posed_normals, path);
                out.once.append(triangles_of(am, posed, posed_normals, mat, materials, path));
            }
            return;
        }
        if (slot[index] < 0) {  // in its own space, once
            slot[index] = static_cast<int>(out.shared.size());
            pose_mesh(s, am, rest, aiMatrix4x4(), nodes, posed, posed_normals, path);
            out.shared.push_back({triangles_of(am, posed, posed_normals, mat, materials, path), {}});
        }
        auto& uses_of = out.shared[static_cast<size_t>(slot[index])].uses;
        uses_of.insert(uses_of.end(), at.begin(), at.end());
    });
    if (out.once.triangle_count() == 0 && out.shared.empty()) throw InputError(path, "", "mesh has no triangles");
    return out;
}

/// Calls fn(face material) for every face of `parts`.
template <typename Fn>
void for_each_face_material(MeshFileParts& parts, Fn&& fn) {
    for (uint32_t& f : parts.once.face_materials) f = fn(f);
    for (MeshFileParts::Shared& s : parts.shared)
        for (uint32_t& f : s.mesh.face_materials) f = fn(f);
}

/// A load through the mesh cache (mesh_cache.h) when the front end gave one: `import` runs
/// only on a miss, and a hit replays what it did (the files it read through `files_read`'s
/// check, the file's materials appended to `materials`).
MeshFileParts through_cache(const std::string& path, const std::string& prefix, bool parts, std::vector<Material>& materials,
                            int override_material, MeshInputs* files_read, const std::function<MeshFileParts(MeshInputs*)>& import) {
    MeshCache* const cache = files_read ? files_read->resources.mesh_cache.get() : nullptr;
    if (!cache || !cache->usable()) return import(files_read);
    const MeshCacheKey key{fs::absolute(path).lexically_normal().string(), prefix, override_material >= 0,
                           override_material >= 0 && materials[static_cast<size_t>(override_material)].is_emissive(), parts};
    const auto base = static_cast<uint32_t>(materials.size());
    auto to_scene = [&](uint32_t f) { return override_material >= 0 ? static_cast<uint32_t>(override_material) : base + f; };
    if (std::optional<LoadedMeshFile> hit = cache->read(key)) {
        for (const auto& input : hit->inputs)
            if (files_read && is_embedded_image(input.first, files_read->resources.images))
                files_read->files.push_back(input.first);  // bounce's own, as on a parse
            else if (files_read)
                files_read->add(input.first);
        materials.insert(materials.end(), hit->materials.begin(), hit->materials.end());
        for_each_face_material(hit->parts, to_scene);
        return std::move(hit->parts);
    }
    MeshInputs read{files_read->check, {}, files_read->resources};  // (a cache folder came from files_read)
    LoadedMeshFile entry{import(&read), {materials.begin() + base, materials.end()}, {}};
    if (files_read) files_read->files.insert(files_read->files.end(), read.files.begin(), read.files.end());
    // By absolute path: a later run from another working directory reads the same files.
    const auto absolute = [](const std::string& f) { return fs::absolute(f).lexically_normal().string(); };
    for (const std::string& f : read.files) entry.inputs.emplace_back(absolute(f), cache->hash(f));
    for (Material& m : entry.materials)
        for (std::string* t : m.texture_files())
            if (!t->empty()) *t = absolute(*t);
    for_each_face_material(entry.parts, [&](uint32_t f) { return override_material >= 0 ? 0 : f - base; });
    cache->write(key, entry);
    for_each_face_material(entry.parts, to_scene);
    return std::move(entry.parts);
}

}  // namespace

TriangleMesh load_mesh_file(const std::string& path, const std::string& prefix, std::vector<Material>& materials, int override_material,
                            MeshInputs* files_read, const MeshPose& pose) {
    if (!pose.clip.empty()) return import_mesh_file(path, prefix, materials, override_material, files_read, pose);
    return through_cache(path, prefix, false, materials, override_material, files_read,
                         [&](MeshInputs* read) {
                             MeshFileParts p;
                             p.once = import_mesh_file(path, prefix, materials, override_material, read, pose);
                             return p;
                         })
        .once;
}

MeshFileParts load_mesh_parts(const std::string& path, const std::string& prefix, std::vector<Material>& materials, int override_material,
                              MeshInputs* files_read) {
    return through_cache(path, prefix, true, materials, override_material, files_read,
                         [&](MeshInputs* read) { return import_mesh_parts(path, prefix, materials, override_material, read); });
}

ControlMesh load_control_mesh(const std::string& path, const std::string& prefix, std::vector<Material>& materials, int override_material,
                              const Transform& transform, MeshInputs* files_read) {
    // Faces stay polygons; vertices are welded by position here (Assimp keeps uv seams apart,
    // which would cut the subdivision surface) and uvs become face-varying values.
    Assimp::Importer imp;
    const aiScene* s = import_file(imp, path, aiProcess_SortByPType | aiProcess_ValidateDataStructure, files_read, override_material < 0);
    const std::vector<uint32_t> mat_map = import_materials(s, path, prefix, materials, override_material, files_read);
    ControlMesh c;
    c.source = path;
    std::map<std::array<float, 3>, int> vertex_of;
    std::map<std::array<float, 2>, int> uv_of;
    bool any_uv = false;
    const bool gltf = is_gltf_file(path);
    for_each_mesh_instance(s, [&](const aiMesh* am, const Transform& t) {
        if (!(am->mPrimitiveTypes & (aiPrimitiveType_POLYGON | aiPrimitiveType_TRIANGLE))) return;
        const aiVector3D* uvs = uv_channel(am, mat_map[am->mMaterialIndex], materials, path);
        any_uv |= uvs != nullptr;
        c.dropped_vertex_colors |= am->mColors[0] && gltf;
        for (unsigned f = 0; f < am->mNumFaces; ++f) {
            const aiFace& face = am->mFaces[f];
            if (face.mNumIndices < 3) continue;
            c.face_sizes.push_back(static_cast<int>(face.mNumIndices));
            c.face_materials.push_back(mat_map[am->mMaterialIndex]);
            for (unsigned i = 0; i < face.mNumIndices; ++i) {
                const unsigned v = face.mIndices[i];
                const Vec3 p = transform.point(t.point(to_vec3(am->mVertices[v])));
                // Before welding: NaN keys would break the map's ordering.
                if (!isfinite(p)) throw InputError(path, fmt::format("vertex {}", v), "position is not finite (after the transforms)");
                auto [it, fresh] = vertex_of.emplace(std::array<float, 3>{p.x, p.y, p.z}, static_cast<int>(c.positions.size()));
                if (fresh) c.positions.push_back(p);
                c.face_vertices.push_back(it->second);
                const Vec2 uv = uvs ? Vec2{uvs[v].x, uvs[v].y} : Vec2{};
                auto [ut, ufresh] = uv_of.emplace(std::array<float, 2>{uv.x, uv.y}, static_cast<int>(c.uvs.size()));
                if (ufresh) c.uvs.push_back(uv);
                c.face_uvs.push_back(ut->second);
            }
        }
    });
    if (!any_uv) c.uvs.clear(), c.face_uvs.clear();
    if (c.face_count() == 0) throw InputError(path, "", "mesh has no polygons");
    for (const Vec3& p : c.positions)
        if (!isfinite(p)) throw InputError(path, "", "mesh has vertex positions that are not finite");
    return c;
}

}  // namespace bounce
