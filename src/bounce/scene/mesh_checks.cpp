#include "bounce/scene/mesh_checks.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string_view>

#include "bounce/core/error.h"
#include "bounce/core/files.h"
#include "bounce/core/json_limits.h"

namespace bounce {

namespace fs = std::filesystem;
using nlohmann::json;

GltfFile read_gltf_file(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    GltfFile f;
    std::string& text = f.bytes;
    text.assign(std::istreambuf_iterator<char>(in), {});
    f.json_size = text.size();
    if (lower_extension(path) != ".glb") return f;
    if (text.size() < 20 || std::memcmp(text.data(), "glTF", 4) != 0)
        throw InputError(path, "byte 0", "not a binary glTF file (no glTF header)");
    uint32_t version = 0, total = 0, len = 0, type = 0;
    std::memcpy(&version, text.data() + 4, 4);
    std::memcpy(&total, text.data() + 8, 4);
    std::memcpy(&len, text.data() + 12, 4);
    std::memcpy(&type, text.data() + 16, 4);
    if (version != 2) throw InputError(path, "byte 4", fmt::format("glTF version {} (bounce reads glTF 2.0)", version));
    if (total > text.size())
        throw InputError(path, "byte 8", fmt::format("truncated: the header declares {} bytes, the file has {}", total, text.size()));
    if (type != 0x4E4F534Au || 20 + static_cast<uint64_t>(len) > text.size())
        throw InputError(path, "byte 12", "truncated or malformed JSON chunk");
    f.json_at = 20, f.json_size = len;
    // The BIN chunk, if any, follows the JSON chunk (padded to 4 bytes).
    const uint64_t bin = 20 + ((static_cast<uint64_t>(len) + 3) & ~uint64_t{3});
    uint32_t bin_len = 0, bin_type = 0;
    if (text.size() >= bin + 8) std::memcpy(&bin_len, text.data() + bin, 4), std::memcpy(&bin_type, text.data() + bin + 4, 4);
    if (bin_type == 0x004E4942u && bin + 8 + bin_len <= text.size()) f.bin_at = bin + 8, f.bin_size = bin_len;
    return f;
}

std::string gltf_json_text(const std::string& path) { return std::string(read_gltf_file(path).json()); }

namespace {

/// Depth of the node hierarchy, walked without recursion; a node reached twice (two parents
/// or a cycle) or a child index out of range is an error.
int gltf_node_depth(const json& nodes, const std::string& path) {
    if (!nodes.is_array()) throw InputError(path, "/nodes", "expected an array");
    const size_t n = nodes.size();
    std::vector<int> parents(n, 0);
    for (size_t i = 0; i < n; ++i) {
        if (!nodes[i].is_object()) throw InputError(path, fmt::format("/nodes/{}", i), "expected an object");
        if (!nodes[i].contains("children")) continue;
        const json& c = nodes[i]["children"];
        if (!c.is_array()) throw InputError(path, fmt::format("/nodes/{}/children", i), "expected an array of node indices");
        for (size_t k = 0; k < c.size(); ++k) {
            if (!c[k].is_number_unsigned() || c[k].get<uint64_t>() >= n)
                throw InputError(path, fmt::format("/nodes/{}/children/{}", i, k), "not a node index");
            if (++parents[c[k].get<size_t>()] > 1)
                throw InputError(path, fmt::format("/nodes/{}/children/{}", i, k),
                                 fmt::format("node {} has two parents (a glTF node tree is a forest)", c[k].get<size_t>()));
        }
    }
    int deepest = 0;
    size_t reached = 0;
    std::vector<std::pair<size_t, int>> stack;
    for (size_t i = 0; i < n; ++i)
        if (parents[i] == 0) stack.emplace_back(i, 1);
    while (!stack.empty()) {
        auto [node, depth] = stack.back();
        stack.pop_back();
        ++reached;
        if (depth > kMaxNodeDepth)
            throw InputError(path, fmt::format("/nodes/{}", node), fmt::format("node hierarchy deeper than {} levels", kMaxNodeDepth));
        deepest = std::max(deepest, depth);
        if (nodes[node].contains("children"))
            for (const json& c : nodes[node]["children"]) stack.emplace_back(c.get<size_t>(), depth + 1);
    }
    if (reached != n) throw InputError(path, "/nodes", "the node hierarchy has a cycle");
    return deepest;
}

/// A data: URI as glTF writes one, "data:<media type>;base64,<data>", its data whole base64
/// (Assimp 5.2 decodes a length that is not a multiple of 4 by reading past it), holding at
/// least `bytes` bytes (a buffer's byteLength: Assimp reads that many).
void check_data_uri(const std::string& uri, size_t bytes, const std::string& where, const std::string& path) {
    const size_t comma = uri.find(',');
    const size_t header_end = comma == std::string::npos ? 0 : comma;
    if (header_end < 12 || uri.compare(header_end - 7, 7, ";base64") != 0)
        throw InputError(path, where, "a data: URI must be \"data:<media type>;base64,<data>\"");
    const std::string_view data(uri.data() + comma + 1, uri.size() - comma - 1);
    const size_t pad = data.ends_with("==") ? 2 : data.ends_with("=") ? 1 : 0;
    const bool alphabet = std::all_of(data.begin(), data.end() - static_cast<std::ptrdiff_t>(pad),
                                      [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '+' || c == '/'; });
    if (data.size() % 4 != 0 || !alphabet)
        throw InputError(path, where,
                         fmt::format("the data of a data: URI is not base64 ({} characters{})", data.size(),
                                     alphabet ? ", not a multiple of 4" : ", some outside its alphabet"));
    if (const size_t holds = data.size() / 4 * 3 - pad; holds < bytes)
        throw InputError(path, where, fmt::format("the data: URI holds {} bytes, fewer than the byteLength {}", holds, bytes));
}

/// Files a glTF's buffers and images name, each required to exist (data: URIs checked instead).
std::vector<std::string> gltf_referenced_files(const json& j, const std::string& path) {
    std::vector<std::string> out;
    for (const char* list : {"buffers", "images"}) {
        if (!j.contains(list)) continue;
        if (!j[list].is_array()) throw InputError(path, std::string("/") + list, "expected an array");
        for (size_t i = 0; i < j[list].size(); ++i) {
            const json& item = j[list][i];
            if (!item.is_object() || !item.contains("uri")) continue;
            const std::string where = fmt::format("/{}/{}/uri", list, i);
            if (!item["uri"].is_string()) throw InputError(path, where, "expected a string");
            const std::string uri = item["uri"].get<std::string>();
            if (uri.rfind("data:", 0) == 0) {
                const json length = item.value("byteLength", json(0));
                check_data_uri(uri, length.is_number_unsigned() ? length.get<size_t>() : 0, where, path);
                continue;
            }
            const fs::path file = (fs::path(path).parent_path() / uri).lexically_normal();
            if (std::string why = not_a_regular_file(file.string()); !why.empty())
                throw InputError(path, where, fmt::format("{}: \"{}\"", why, file.string()));
            out.push_back(file.string());
        }
    }
    return out;
}

/// Indices into `list` held at `ptr` of `j` (a number, or every element of an array).
void check_indices(const json& j, const std::string& ptr, size_t count, const std::string& what, const std::string& path) {
    const auto one = [&](const json& v, const std::string& at) {
        if (!v.is_number_unsigned() || v.get<uint64_t>() >= count)
            throw InputError(path, at, fmt::format("{} is not a {} index (the file has {})", v.dump(), what, count));
    };
    if (j.is_array())
        for (size_t i = 0; i < j.size(); ++i) one(j[i], fmt::format("{}/{}", ptr, i));
    else
        one(j, ptr);
}

/// Skins and animations name nodes and accessors that exist (Assimp's own message names no place).
void check_gltf_references(const json& j, const std::string& path) {
    const size_t nodes = j.contains("nodes") && j["nodes"].is_array() ? j["nodes"].size() : 0;
    const size_t accessors = j.contains("accessors") && j["accessors"].is_array() ? j["accessors"].size() : 0;
    if (j.contains("skins") && j["skins"].is_array())
        for (size_t s = 0; s < j["skins"].size(); ++s) {
            const json& skin = j["skins"][s];
            if (!skin.is_object()) continue;
            if (skin.contains("joints")) check_indices(skin["joints"], fmt::format("/skins/{}/joints", s), nodes, "node", path);
            // glTF lets a skin leave them out (identity), but Assimp 5.2 then reads through a null
            // accessor and crashes (found by mesh_file_fuzz): refused, naming the fix.
            if (!skin.contains("inverseBindMatrices"))
                throw InputError(path, fmt::format("/skins/{}", s),
                                 "a skin without inverseBindMatrices cannot be read (Assimp 5 crashes on it); write identity matrices");
            check_indices(skin["inverseBindMatrices"], fmt::format("/skins/{}/inverseBindMatrices", s), accessors, "accessor", path);
        }
    if (!j.contains("animations") || !j["animations"].is_array()) return;
    for (size_t a = 0; a < j["animations"].size(); ++a) {
        const json& anim = j["animations"][a];
        if (!anim.is_object() || !anim.contains("channels") || !anim["channels"].is_array()) continue;
        for (size_t c = 0; c < anim["channels"].size(); ++c) {
            const json& ch = anim["channels"][c];
            // glTF requires a target: Assimp 5.2 dereferences a channel's missing one (a SEGV the
            // mesh fuzzer's 30-minute run found).
            if (!ch.is_object() || !ch.contains("target") || !ch["target"].is_object())
                throw InputError(path, fmt::format("/animations/{}/channels/{}", a, c), "an animation channel needs a \"target\" object");
            if (ch["target"].contains("node"))
                check_indices(ch["target"]["node"], fmt::format("/animations/{}/channels/{}/target/node", a, c), nodes, "node", path);
        }
    }
}

/// The element count of accessor `index` (-1 when it or its count is not there: check_indices
/// and Assimp speak of those).
int64_t accessor_count(const json& j, const json& index) {
    if (!index.is_number_unsigned() || !j.contains("accessors") || !j["accessors"].is_array()) return -1;
    const auto i = index.get<size_t>();
    if (i >= j["accessors"].size() || !j["accessors"][i].is_object()) return -1;
    const json& count = j["accessors"][i].value("count", json());
    return count.is_number_unsigned() ? count.get<int64_t>() : -1;
}

/// Counts that must agree: a primitive's attributes and a morph target's elements with its
/// vertices, a skin's inverse bind matrices with its joints (Assimp accepted fewer and read past them, or left
/// the matrices out and failed later with no place).
void check_gltf_counts(const json& j, const std::string& path) {
    if (j.contains("meshes") && j["meshes"].is_array())
        for (size_t m = 0; m < j["meshes"].size(); ++m) {
            const json& prims = j["meshes"][m].is_object() ? j["meshes"][m].value("primitives", json()) : json();
            for (size_t p = 0; prims.is_array() && p < prims.size(); ++p) {
                if (!prims[p].is_object() || !prims[p].contains("attributes") || !prims[p]["attributes"].is_object()) continue;
                const int64_t vertices = accessor_count(j, prims[p]["attributes"].value("POSITION", json()));
                // Every attribute has one element per vertex (glTF 2.0, 3.7.2.1): a COLOR_0 or
                // TEXCOORD_1 of another count would be read past its end or left short.
                for (const auto& [name, index] : prims[p]["attributes"].items()) {
                    const int64_t n = accessor_count(j, index);
                    if (vertices >= 0 && n >= 0 && n != vertices)
                        throw InputError(path, fmt::format("/meshes/{}/primitives/{}/attributes/{}", m, p, name.substr(0, 40)),
                                         fmt::format("{} elements for the primitive's {} vertices", n, vertices));
                }
                if (!prims[p].contains("targets")) continue;
                const json& targets = prims[p]["targets"];
                for (size_t t = 0; vertices >= 0 && targets.is_array() && t < targets.size(); ++t) {
                    if (!targets[t].is_object()) continue;
                    for (const auto& [name, index] : targets[t].items()) {
                        const int64_t n = accessor_count(j, index);
                        if (n >= 0 && n != vertices)
                            throw InputError(path, fmt::format("/meshes/{}/primitives/{}/targets/{}/{}", m, p, t, name),
                                             fmt::format("{} elements for the primitive's {} vertices", n, vertices));
                    }
                }
            }
        }
    if (!j.contains("skins") || !j["skins"].is_array()) return;
    for (size_t s = 0; s < j["skins"].size(); ++s) {
        const json& skin = j["skins"][s];
        if (!skin.is_object() || !skin.contains("inverseBindMatrices") || !skin.contains("joints") || !skin["joints"].is_array()) continue;
        const int64_t n = accessor_count(j, skin["inverseBindMatrices"]);
        if (n >= 0 && n < static_cast<int64_t>(skin["joints"].size()))
            throw InputError(path, fmt::format("/skins/{}/inverseBindMatrices", s),
                             fmt::format("{} matrices for the skin's {} joints", n, skin["joints"].size()));
    }
}

std::vector<std::string> check_gltf(const std::string& path) {
    const std::string text = gltf_json_text(path);
    check_json_nesting(text, path);
    json j;
    try {
        j = json::parse(text);
    } catch (const json::exception& e) {
        std::string msg = e.what();
        const auto pos = msg.find("] ");
        throw InputError(path, "", "malformed glTF JSON (truncated?): " + (pos == std::string::npos ? msg : msg.substr(pos + 2)));
    }
    if (!j.is_object()) throw InputError(path, "", "a glTF file holds a JSON object");
    if (j.contains("nodes")) gltf_node_depth(j["nodes"], path);
    check_gltf_references(j, path);
    check_gltf_counts(j, path);
    return gltf_referenced_files(j, path);
}

/// An OBJ's MTL files (mtllib lines), each counted: more materials than kMaxMtlMaterials is refused.
std::vector<std::string> check_obj(const std::string& path, const MeshCheckOptions& options) {
    std::ifstream in(path, std::ios::binary);
    std::vector<std::string> out;
    size_t line_number = 0;
    for (std::string line; std::getline(in, line);) {
        ++line_number;
        if (line.rfind("mtllib", 0) != 0) continue;
        std::istringstream ls(line.substr(6));
        for (std::string name; ls >> name;) {
            const fs::path mtl = (fs::path(path).parent_path() / name).lexically_normal();
            if (options.before_open) options.before_open(mtl.string());  // refused before it is opened
            if (const std::string why = not_a_regular_file(mtl.string()); !why.empty()) {
                // Assimp would warn and give every face its default material: with the file's
                // own materials in use, that is a wrong image in silence.
                if (options.own_materials)
                    throw InputError(path, fmt::format("line {}", line_number), fmt::format("mtllib {}: {}", name, why));
                continue;
            }
            std::ifstream m(mtl, std::ios::binary);
            size_t count = 0, lineno = 0;
            for (std::string l; std::getline(m, l);) {
                ++lineno;
                const size_t at = l.find_first_not_of(" \t");
                if (at != std::string::npos && l.compare(at, 6, "newmtl") == 0 && ++count > kMaxMtlMaterials)
                    throw InputError(mtl.string(), fmt::format("line {}", lineno), fmt::format("more than {} materials", kMaxMtlMaterials));
            }
            out.push_back(mtl.string());
        }
    }
    return out;
}

}  // namespace

bool is_gltf_file(const std::string& path) {
    const std::string ext = lower_extension(path);
    return ext == ".gltf" || ext == ".glb";
}

std::vector<std::string> check_mesh_file(const std::string& path, const MeshCheckOptions& options) {
    const std::string ext = lower_extension(path);
    if (ext == ".ply") check_ply_counts(path);
    if (is_gltf_file(path)) return check_gltf(path);
    if (ext == ".obj") return check_obj(path, options);
    return {};
}

}  // namespace bounce
