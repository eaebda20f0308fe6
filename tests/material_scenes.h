// Scenes the material tests share (issue 61): a card in front of a wall, under a quad light,
// written in the scene file or as a glTF quad with a given material.
#pragma once

#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>

#include <string>
#include <vector>

#include "bounce/render/render.h"
#include "gltf_strip.h"
#include "test_util.h"

namespace bounce::test_scenes {

using nlohmann::json;

/// Writes a w x h 8-bit PNG of `channels` channels of `values` (rows from the top, 0..255).
inline void write_png(const std::string& path, int w, int h, int channels, const std::vector<unsigned char>& values) {
    auto out = OIIO::ImageOutput::create(path);
    ASSERT_TRUE(out);
    OIIO::ImageSpec spec(w, h, channels, OIIO::TypeDesc::UINT8);
    if (channels == 4) spec.alpha_channel = 3;
    ASSERT_TRUE(out->open(path, spec) && out->write_image(OIIO::TypeDesc::UINT8, values.data()) && out->close());
}
inline void write_grey(const std::string& path, int w, int h, const std::vector<unsigned char>& values) {
    write_png(path, w, h, 1, values);
}

inline json quad(const std::string& name, const std::string& material, double x0, double x1, double y0, double y1, double z) {
    // uv (0, 0) at the first vertex, u along x, v along y (geometry/mesh.h's make_quad).
    return {{"name", name}, {"type", "quad"}, {"material", material}, {"vertices", {{x0, y0, z}, {x1, y0, z}, {x1, y1, z}, {x0, y1, z}}}};
}

/// A floor and a back wall under a small quad light, a card at z = 0 in front of the wall casting a
/// shadow on the floor, and `card` objects.
inline json stage(const json& card, const json& card_material) {
    json j = {
        {"camera", {{"position", {0, 1.6, -6}}, {"look_at", {0, 1, 0}}, {"fov", 45}, {"resolution", {48, 36}}}},
        {"render", {{"spp", 4}, {"light_samples", 2}, {"seed", 7}, {"rays", 16}}},
        {"materials", {{"white", {{"color", 0.7}}}, {"leaf", card_material}}},
        {"lights", {{{"type", "quad"}, {"corner", {0.1, 4, -3.2}}, {"edge_u", {0.4, 0, 0}}, {"edge_v", {0, 0, 0.4}}, {"color", 200}}}},
        {"objects",
         {{{"name", "floor"}, {"type", "quad"}, {"material", "white"}, {"vertices", {{-6, 0, -6}, {-6, 0, 6}, {6, 0, 6}, {6, 0, -6}}}},
          quad("back", "white", -6, 6, 0, 6, 3)}}};
    for (const json& o : card) j["objects"].push_back(o);
    return j;
}

inline Image render_with(const json& scene, const std::string& gi, const std::vector<Override>& more = {}) {
    Stats stats;
    std::vector<Override> o{Override("render.gi=" + gi)};
    o.insert(o.end(), more.begin(), more.end());
    return render(test::scene_from(scene, o), {}, stats, nullptr).image;
}

inline const json kLeaf = {{"color", {0.2, 0.6, 0.1}}};

/// The card of `stage` as a glTF quad (buffers inline) with `material`; its uvs are the JSON
/// quad's (glTF's v runs down the image: Assimp turns it up). `second_uvs`: they are its
/// TEXCOORD_1, and its TEXCOORD_0 reads one point of a texture everywhere.
inline std::string gltf_card(const test::TempDir& dir, const json& material, bool second_uvs = false) {
    std::string b;
    test::put<float>(b, {-1, 0.2f, 0, 1, 0.2f, 0, 1, 2.2f, 0, -1, 2.2f, 0});  // 48 bytes
    if (second_uvs)
        test::put<float>(b, {0.5f, 0.5f, 0.5f, 0.5f, 0.5f, 0.5f, 0.5f, 0.5f});  // one texel everywhere
    else
        test::put<float>(b, {0, 1, 1, 1, 1, 0, 0, 0});  // 32 bytes: TEXCOORD_0
    test::put<uint16_t>(b, {0, 1, 2, 0, 2, 3});         // 12 bytes
    test::put<float>(b, {0, 1, 1, 1, 1, 0, 0, 0});      // 32 bytes: TEXCOORD_1
    json g = {{"asset", {{"version", "2.0"}}}, {"scene", 0}, {"scenes", {{{"nodes", {0}}}}}, {"nodes", {{{"mesh", 0}}}}};
    g["buffers"] = {{{"byteLength", b.size()}, {"uri", "data:application/octet-stream;base64," + test::base64(b)}}};
    g["bufferViews"] = {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 48}},
                        {{"buffer", 0}, {"byteOffset", 48}, {"byteLength", 32}},
                        {{"buffer", 0}, {"byteOffset", 80}, {"byteLength", 12}},
                        {{"buffer", 0}, {"byteOffset", 92}, {"byteLength", 32}}};
    g["accessors"] = {
        {{"bufferView", 0}, {"componentType", 5126}, {"count", 4}, {"type", "VEC3"}, {"min", {-1, 0.2, 0}}, {"max", {1, 2.2, 0}}},
        {{"bufferView", 1}, {"componentType", 5126}, {"count", 4}, {"type", "VEC2"}},
        {{"bufferView", 2}, {"componentType", 5123}, {"count", 6}, {"type", "SCALAR"}},
        {{"bufferView", 3}, {"componentType", 5126}, {"count", 4}, {"type", "VEC2"}}};
    json primitive = {{"attributes", {{"POSITION", 0}, {"TEXCOORD_0", 1}}}, {"indices", 2}, {"material", 0}};
    if (second_uvs) primitive["attributes"]["TEXCOORD_1"] = 3;
    g["meshes"] = json::array({json{{"primitives", json::array({primitive})}}});
    g["materials"] = {material};
    g["images"] = {{{"uri", "leaf.png"}}};
    g["textures"] = {{{"source", 0}}};
    return dir.write("card.gltf", g.dump());
}

/// A PNG whose header says 30000 x 30000 (its pixels never read): a texture refused by its size.
inline std::string write_huge_png(const test::TempDir& dir) {
    const auto crc = [](const std::string& bytes) {
        uint32_t c = 0xffffffffu;
        for (unsigned char b : bytes) {
            c ^= b;
            for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0xedb88320u & (0u - (c & 1u)));
        }
        return c ^ 0xffffffffu;
    };
    const auto be32 = [](uint32_t v) {
        return std::string{static_cast<char>(v >> 24), static_cast<char>(v >> 16), static_cast<char>(v >> 8), static_cast<char>(v)};
    };
    const auto chunk = [&](const std::string& kind, const std::string& data) {
        return be32(static_cast<uint32_t>(data.size())) + kind + data + be32(crc(kind + data));
    };
    return dir.write("huge.png", std::string("\x89PNG\r\n\x1a\n", 8) +
                                     chunk("IHDR", be32(30000) + be32(30000) + std::string("\x08\x00\x00\x00\x00", 5)) +
                                     chunk("IDAT", std::string("\x78\x9c\x03\x00\x00\x00\x00\x01", 8)) + chunk("IEND", ""));
}

}  // namespace bounce::test_scenes
