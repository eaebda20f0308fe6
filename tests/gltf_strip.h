// A two-joint skinned strip as an inline glTF (buffers as a data URI), written by the tests
// that pose it (glTF animation, motion blur of a deforming mesh).
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <string>

namespace bounce::test {

inline std::string base64(const std::string& bytes) {
    static const char* t = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    for (size_t i = 0; i < bytes.size(); i += 3) {
        const uint32_t n = (static_cast<uint8_t>(bytes[i]) << 16) | (i + 1 < bytes.size() ? static_cast<uint8_t>(bytes[i + 1]) << 8 : 0) |
                           (i + 2 < bytes.size() ? static_cast<uint8_t>(bytes[i + 2]) : 0);
        out += t[(n >> 18) & 63], out += t[(n >> 12) & 63];
        out += i + 1 < bytes.size() ? t[(n >> 6) & 63] : '=';
        out += i + 2 < bytes.size() ? t[n & 63] : '=';
    }
    return out;
}

template <typename T>
inline void put(std::string& b, std::initializer_list<T> values) {
    for (T v : values) b.append(reinterpret_cast<const char*>(&v), sizeof(T));
}

/// A strip from x = 0 to 2 (y from 0 to 1) in two cells, skinned to a root joint at the origin
/// and a second joint at x = 1 whose rotation about z goes from 0 to 90 degrees over 1 second.
/// Vertices at x = 2 follow the second joint alone; the rest the root.
/// `times`: the animation's two key times (seconds).
inline nlohmann::json skinned_strip(int joint_of_tip = 1, float tip_weight = 1, std::array<float, 2> times = {0, 1}) {
    std::string b;
    put<float>(b, {0, 0, 0, 1, 0, 0, 2, 0, 0, 0, 1, 0, 1, 1, 0, 2, 1, 0});                                          // 6 positions: 72 bytes
    put<uint16_t>(b, {0, 1, 4, 0, 4, 3, 1, 2, 5, 1, 5, 4});                                                         // 12 indices: 24 bytes
    for (int v = 0; v < 6; ++v) put<uint16_t>(b, {static_cast<uint16_t>(v % 3 == 2 ? joint_of_tip : 0), 0, 0, 0});  // 48 bytes
    for (int v = 0; v < 6; ++v) put<float>(b, {v % 3 == 2 ? tip_weight : 1.0f, 0, 0, 0});                           // 96 bytes
    put<float>(b, {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, -1, 0, 0, 1});  // 128 bytes
    put<float>(b, {times[0], times[1]});                                                                               // 8 bytes: key times
    const float h = std::sqrt(0.5f);
    put<float>(b, {0, 0, 0, 1, 0, 0, h, h});  // 32 bytes: quaternions (x, y, z, w)
    using nlohmann::json;
    json g = {{"asset", {{"version", "2.0"}}}, {"scene", 0}, {"scenes", {{{"nodes", {0, 2}}}}}};
    g["buffers"] = {{{"byteLength", b.size()}, {"uri", "data:application/octet-stream;base64," + base64(b)}}};
    const auto view = [](int offset, int length) { return json{{"buffer", 0}, {"byteOffset", offset}, {"byteLength", length}}; };
    g["bufferViews"] = {view(0, 72), view(72, 24), view(96, 48), view(144, 96), view(240, 128), view(368, 8), view(376, 32)};
    g["accessors"] = {{{"bufferView", 0}, {"componentType", 5126}, {"count", 6}, {"type", "VEC3"}, {"min", {0, 0, 0}}, {"max", {2, 1, 0}}},
                      {{"bufferView", 1}, {"componentType", 5123}, {"count", 12}, {"type", "SCALAR"}},
                      {{"bufferView", 2}, {"componentType", 5123}, {"count", 6}, {"type", "VEC4"}},
                      {{"bufferView", 3}, {"componentType", 5126}, {"count", 6}, {"type", "VEC4"}},
                      {{"bufferView", 4}, {"componentType", 5126}, {"count", 2}, {"type", "MAT4"}},
                      {{"bufferView", 5}, {"componentType", 5126}, {"count", 2}, {"type", "SCALAR"}, {"min", {0}}, {"max", {1}}},
                      {{"bufferView", 6}, {"componentType", 5126}, {"count", 2}, {"type", "VEC4"}}};
    json primitive = {{"attributes", {{"POSITION", 0}, {"JOINTS_0", 2}, {"WEIGHTS_0", 3}}}, {"indices", 1}};
    g["meshes"] = json::array({json{{"primitives", json::array({primitive})}}});
    g["nodes"] = {{{"name", "root"}, {"children", {1}}},
                  {{"name", "elbow"}, {"translation", {1, 0, 0}}},
                  {{"name", "strip"}, {"mesh", 0}, {"skin", 0}}};
    g["skins"] = {{{"joints", {0, 1}}, {"inverseBindMatrices", 4}}};
    json sampler = {{"input", 5}, {"output", 6}, {"interpolation", "LINEAR"}};
    json channel = {{"sampler", 0}, {"target", {{"node", 1}, {"path", "rotation"}}}};
    g["animations"] = json::array({json{{"name", "bend"}, {"samplers", json::array({sampler})}, {"channels", json::array({channel})}}});
    return g;
}

/// A unit quad at x in [3, 4], y in [0, 1] with one morph target that lifts its top edge by 1,
/// its weight animated from 0 to 1 over 1 second (clip "rise"). The node is "blob"; the mesh is
/// named `mesh_name` (empty: unnamed), which glTF does not tie to the node's name.
inline nlohmann::json morphed_quad(const std::string& mesh_name = "") {
    std::string b;
    put<float>(b, {3, 0, 0, 4, 0, 0, 4, 1, 0, 3, 1, 0});        // 4 positions: 48 bytes
    put<uint16_t>(b, {0, 1, 2, 0, 2, 3});                       // 6 indices: 12 bytes
    put<float>(b, {0, 0, 0, 0, 0, 0, 0, 1, 0.5f, 0, 1, 0.5f});  // the target's displacements: 48 bytes
    put<float>(b, {0, 1});                                      // 8 bytes: key times
    put<float>(b, {0, 1});                                      // 8 bytes: the weight at each key
    using nlohmann::json;
    json g = {{"asset", {{"version", "2.0"}}}, {"scene", 0}, {"scenes", {{{"nodes", {0}}}}}};
    g["buffers"] = {{{"byteLength", b.size()}, {"uri", "data:application/octet-stream;base64," + base64(b)}}};
    const auto view = [](int offset, int length) { return json{{"buffer", 0}, {"byteOffset", offset}, {"byteLength", length}}; };
    g["bufferViews"] = {view(0, 48), view(48, 12), view(60, 48), view(108, 8), view(116, 8)};
    g["accessors"] = {
        {{"bufferView", 0}, {"componentType", 5126}, {"count", 4}, {"type", "VEC3"}, {"min", {3, 0, 0}}, {"max", {4, 1, 0}}},
        {{"bufferView", 1}, {"componentType", 5123}, {"count", 6}, {"type", "SCALAR"}},
        {{"bufferView", 2}, {"componentType", 5126}, {"count", 4}, {"type", "VEC3"}, {"min", {0, 0, 0}}, {"max", {0, 1, 0.5}}},
        {{"bufferView", 3}, {"componentType", 5126}, {"count", 2}, {"type", "SCALAR"}, {"min", {0}}, {"max", {1}}},
        {{"bufferView", 4}, {"componentType", 5126}, {"count", 2}, {"type", "SCALAR"}}};
    json primitive = {{"attributes", {{"POSITION", 0}}}, {"indices", 1}, {"targets", json::array({json{{"POSITION", 2}}})}};
    json mesh = {{"primitives", json::array({primitive})}, {"weights", {0}}};
    if (!mesh_name.empty()) mesh["name"] = mesh_name;
    g["meshes"] = json::array({mesh});
    g["nodes"] = {{{"name", "blob"}, {"mesh", 0}}};
    json sampler = {{"input", 3}, {"output", 4}, {"interpolation", "LINEAR"}};
    json channel = {{"sampler", 0}, {"target", {{"node", 0}, {"path", "weights"}}}};
    g["animations"] = json::array({json{{"name", "rise"}, {"samplers", json::array({sampler})}, {"channels", json::array({channel})}}});
    return g;
}

}  // namespace bounce::test
