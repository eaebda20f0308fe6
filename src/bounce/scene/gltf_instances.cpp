#include "bounce/scene/gltf_instances.h"

#include <fmt/format.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "bounce/core/error.h"
#include "bounce/scene/mesh_checks.h"

namespace bounce {

using nlohmann::json;

namespace {

constexpr const char* kExtension = "EXT_mesh_gpu_instancing";

std::string decode_base64(const std::string& in, const std::string& path, const std::string& at) {
    std::string out;
    uint32_t bits = 0;
    int held = 0;
    for (char c : in) {
        int v = c >= 'A' && c <= 'Z'   ? c - 'A'
                : c >= 'a' && c <= 'z' ? c - 'a' + 26
                : c >= '0' && c <= '9' ? c - '0' + 52
                : c == '+'             ? 62
                : c == '/'             ? 63
                : c == '='             ? -2
                                       : -1;
        if (v == -2) break;
        if (v < 0) throw InputError(path, at, "the data URI is not base64");
        bits = (bits << 6) | static_cast<uint32_t>(v), held += 6;
        if (held >= 8) held -= 8, out += static_cast<char>((bits >> held) & 0xff);
    }
    return out;
}

/// The bytes of the file's buffers, read when first asked for (a data URI, a file beside the
/// glTF, or a .glb's BIN chunk).
class Buffers {
  public:
    Buffers(const json& j, std::string path, std::string_view bin) : j_(j), path_(std::move(path)), bin_(bin) {}
    const std::string& get(size_t index) {
        if (auto it = loaded_.find(index); it != loaded_.end()) return it->second;
        const std::string at = fmt::format("/buffers/{}", index);
        if (!j_.contains("buffers") || !j_["buffers"].is_array() || index >= j_["buffers"].size())
            throw InputError(path_, at, "no such buffer");
        const json& b = j_["buffers"][index];
        const std::string uri = b.is_object() ? b.value("uri", std::string()) : std::string();
        std::string bytes;
        if (uri.rfind("data:", 0) == 0) {
            const size_t comma = uri.find(',');
            if (comma == std::string::npos) throw InputError(path_, at + "/uri", "a data URI without data");
            bytes = decode_base64(uri.substr(comma + 1), path_, at + "/uri");
        } else if (!uri.empty()) {
            // (check_mesh_file saw this file first: a regular file inside the confinement.)
            std::ifstream in(std::filesystem::path(path_).parent_path() / uri, std::ios::binary);
            bytes.assign(std::istreambuf_iterator<char>(in), {});
        } else {
            if (bin_.empty()) throw InputError(path_, at, "a buffer without a uri needs a .glb's BIN chunk");
            bytes = bin_;
        }
        return loaded_.emplace(index, std::move(bytes)).first->second;
    }

  private:
    const json& j_;
    std::string path_;
    std::string_view bin_;  ///< a .glb's BIN chunk (empty: none)
    std::unordered_map<size_t, std::string> loaded_;
};

/// Accessor `index` as `components` floats per element (float, or for a rotation normalized
/// bytes and shorts, as the extension allows).
std::vector<float> read_accessor(const json& j, const json& index, int components, bool rotation, Buffers& buffers, const std::string& path,
                                 const std::string& at) {
    const auto fail = [&](const std::string& why) -> std::vector<float> { throw InputError(path, at, why); };
    if (!index.is_number_unsigned() || !j.contains("accessors") || index.get<size_t>() >= j["accessors"].size())
        return fail("not an accessor");
    const json& a = j["accessors"][index.get<size_t>()];
    if (!a.is_object() || !a.contains("bufferView") || a.contains("sparse"))
        return fail("an accessor with a bufferView (and not sparse) is needed");
    const int type = a.value("componentType", 0);
    const size_t size = type == 5126 ? 4 : rotation && type == 5122 ? 2 : rotation && type == 5120 ? 1 : 0;
    if (size == 0) return fail(rotation ? "ROTATION must be floats or normalized bytes or shorts" : "expected floats (componentType 5126)");
    if (size < 4 && !a.value("normalized", false)) return fail("ROTATION of bytes or shorts must be normalized (\"normalized\": true)");
    if (a.value("type", std::string()) != (components == 3 ? "VEC3" : "VEC4"))
        return fail(components == 3 ? "expected a VEC3 accessor" : "expected a VEC4 accessor");
    const size_t count = a.value("count", size_t{0}),
                 view_index = a["bufferView"].is_number_unsigned() ? a["bufferView"].get<size_t>() : SIZE_MAX;
    if (!j.contains("bufferViews") || view_index >= j["bufferViews"].size()) return fail("its bufferView does not exist");
    const json& v = j["bufferViews"][view_index];
    const size_t element = size * static_cast<size_t>(components), stride = v.value("byteStride", element);
    const size_t view_offset = v.value("byteOffset", size_t{0}), own_offset = a.value("byteOffset", size_t{0});
    const size_t span = v.value("byteLength", size_t{0});
    const std::string& bytes = buffers.get(v.value("buffer", size_t{0}));
    // Each bound below the buffer's size first, so that no product or sum can overflow.
    if (count == 0 || stride < element || view_offset > bytes.size() || span > bytes.size() - view_offset || own_offset > span ||
        count > span || stride > span || stride * (count - 1) + element > span - own_offset)
        return fail(fmt::format("its {} elements do not fit in their bufferView and buffer", count));
    const size_t first = view_offset + own_offset;
    std::vector<float> out;
    out.reserve(count * static_cast<size_t>(components));
    for (size_t e = 0; e < count; ++e)
        for (size_t c = 0; c < static_cast<size_t>(components); ++c) {
            const char* p = bytes.data() + first + e * stride + c * size;
            float x = 0;
            if (size == 4)
                std::memcpy(&x, p, 4);
            else if (size == 2) {
                int16_t v16 = 0;
                std::memcpy(&v16, p, 2);
                x = std::max(static_cast<float>(v16) / 32767.0f, -1.0f);
            } else
                x = std::max(static_cast<float>(static_cast<int8_t>(*p)) / 127.0f, -1.0f);
            if (!std::isfinite(x) || std::abs(x) > kMaxCoordinate)
                return fail(fmt::format("element {} is not finite or beyond +-{:g}", e, kMaxCoordinate));
            out.push_back(x);
        }
    return out;
}

/// Translation x rotation (unit quaternion x, y, z, w) x scale.
Transform trs(const float* t, const float* q, const float* s) {
    const float len = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    const float x = q[0] / len, y = q[1] / len, z = q[2] / len, w = q[3] / len;
    Transform r;
    r.m = {1 - 2 * (y * y + z * z),
           2 * (x * y - z * w),
           2 * (x * z + y * w),
           t[0],
           2 * (x * y + z * w),
           1 - 2 * (x * x + z * z),
           2 * (y * z - x * w),
           t[1],
           2 * (x * z - y * w),
           2 * (y * z + x * w),
           1 - 2 * (x * x + y * y),
           t[2],
           0,
           0,
           0,
           1};
    return r * Transform::scale({s[0], s[1], s[2]});
}

/// Node `node`'s instances, from its extension object `ext`.
GpuInstances node_instances(const json& j, size_t node, const json& ext, Buffers& buffers, const std::string& path) {
    GpuInstances g{fmt::format("/nodes/{}/extensions/{}", node, kExtension), {}};
    if (!j["nodes"][node].contains("mesh")) throw InputError(path, g.pointer, "instances of a node without a mesh");
    if (!ext.is_object() || !ext.contains("attributes") || !ext["attributes"].is_object())
        throw InputError(path, g.pointer, "expected {\"attributes\": {\"TRANSLATION\", \"ROTATION\", \"SCALE\"}}");
    const json& attributes = ext["attributes"];
    std::vector<float> t, r, s;
    const auto read = [&](const char* key, int components, std::vector<float>& out) {
        if (attributes.contains(key))
            out = read_accessor(j, attributes[key], components, components == 4, buffers, path, g.pointer + "/attributes/" + key);
    };
    read("TRANSLATION", 3, t), read("ROTATION", 4, r), read("SCALE", 3, s);
    const size_t count = !t.empty() ? t.size() / 3 : !r.empty() ? r.size() / 4 : s.size() / 3;
    if (count == 0) throw InputError(path, g.pointer + "/attributes", "none of TRANSLATION, ROTATION, SCALE");
    if ((!t.empty() && t.size() != 3 * count) || (!r.empty() && r.size() != 4 * count) || (!s.empty() && s.size() != 3 * count))
        throw InputError(path, g.pointer + "/attributes", "TRANSLATION, ROTATION and SCALE have different counts");
    const float zero[3] = {0, 0, 0}, unit[4] = {0, 0, 0, 1}, one[3] = {1, 1, 1};
    for (size_t i = 0; i < count; ++i) {
        const float* q = r.empty() ? unit : &r[4 * i];
        if (!(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3] > 1e-12f))
            throw InputError(path, g.pointer + "/attributes/ROTATION", fmt::format("instance {} has a zero quaternion", i));
        g.at.push_back(trs(t.empty() ? zero : &t[3 * i], q, s.empty() ? one : &s[3 * i]));
    }
    return g;
}

/// Assimp's node for every glTF node, walking both trees in step (Assimp keeps the file's
/// hierarchy: one root node as its root, several under a root of its own).
std::unordered_map<size_t, const aiNode*> match_nodes(const json& j, const aiScene* s, const std::string& path) {
    std::unordered_map<size_t, const aiNode*> out;
    const size_t scene = j.value("scene", size_t{0});
    const json roots =
        j.contains("scenes") && scene < j["scenes"].size() ? j["scenes"][scene].value("nodes", json::array()) : json::array();
    std::vector<std::pair<size_t, const aiNode*>> stack;
    if (roots.size() == 1)
        stack.emplace_back(roots[0].get<size_t>(), s->mRootNode);
    else if (roots.size() == s->mRootNode->mNumChildren)
        for (size_t c = 0; c < roots.size(); ++c) stack.emplace_back(roots[c].get<size_t>(), s->mRootNode->mChildren[c]);
    while (!stack.empty()) {
        const auto [node, ai] = stack.back();
        stack.pop_back();
        if (node >= j["nodes"].size()) throw InputError(path, fmt::format("/scenes/{}/nodes", scene), "not a node index");
        const json children = j["nodes"][node].value("children", json::array());
        if (children.size() != ai->mNumChildren)
            throw InputError(path, fmt::format("/nodes/{}", node), "cannot match the file's nodes to the importer's (instances need them)");
        out.emplace(node, ai);
        for (size_t c = 0; c < children.size(); ++c) stack.emplace_back(children[c].get<size_t>(), ai->mChildren[c]);
    }
    return out;
}

std::unordered_map<const aiNode*, GpuInstances> read_gpu_instances(const std::string& path, const json& j, std::string_view bin,
                                                                   const aiScene* s) {
    std::unordered_map<const aiNode*, GpuInstances> out;
    if (!j.contains("nodes") || !j["nodes"].is_array()) return out;
    Buffers buffers(j, path, bin);
    std::unordered_map<size_t, const aiNode*> nodes;
    for (size_t n = 0; n < j["nodes"].size(); ++n) {
        const json& e = j["nodes"][n].value("extensions", json::object());
        if (!e.is_object() || !e.contains(kExtension)) continue;
        if (nodes.empty()) nodes = match_nodes(j, s, path);
        const auto it = nodes.find(n);
        if (it == nodes.end()) continue;  // not in the scene shown
        out.emplace(it->second, node_instances(j, n, e[kExtension], buffers, path));
    }
    return out;
}
}  // namespace

std::unordered_map<const aiNode*, GpuInstances> gltf_gpu_instances(const std::string& path, const aiScene* s) {
    if (!is_gltf_file(path)) return {};
    const GltfFile file = read_gltf_file(path);  // (once: its JSON and a .glb's BIN chunk)
    if (file.json().find(kExtension) == std::string_view::npos) return {};
    try {
        return read_gpu_instances(path, json::parse(file.json()), file.bin(), s);  // (check_mesh_file parsed it already)
    } catch (const json::exception& e) {
        // A count, offset, index or name of the wrong JSON type where the extension reads it.
        std::string why = e.what();
        const auto at = why.find("] ");
        throw InputError(path, "",
                         "malformed glTF where EXT_mesh_gpu_instancing reads it: " + (at == std::string::npos ? why : why.substr(at + 2)));
    }
}

}  // namespace bounce
