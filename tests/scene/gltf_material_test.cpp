// The whole glTF material (issue 61, item 2): each part bounce reads is the same scene written
// in bounce's JSON, bit for bit (texture transforms, a second uv set, metallic-roughness and
// emission textures, transmission onto glass), emission textures light the scene as a textured
// quad light does, what is not read is named, and hostile values are refused naming the place.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <numbers>

#include "bounce/scene/mesh_cache.h"
#include "bounce/scene/surface_textures.h"
#include "material_scenes.h"
#include "test_util.h"

namespace bounce {
namespace {

using nlohmann::json;
using namespace test_scenes;

const json kCardObject = {{"name", "card"}, {"type", "mesh"}};

json card_from(const std::string& file) {
    json o = kCardObject;
    o["file"] = file;
    return json::array({o});
}
const json kWrittenCard = json::array({quad("card", "leaf", -1, 1, 0.2, 2.2, 0)});

/// Four texels across: dark, light, mid, light (RGB).
void write_stripes(const std::string& path) { write_png(path, 4, 1, 3, {30, 60, 90, 250, 240, 230, 120, 140, 160, 255, 255, 255}); }

/// The card's pixels: where the albedo is not the wall's grey 0.7 nor the floor's.
size_t card_pixels(const Image& img) {
    const Layer* albedo = img.find("albedo");
    size_t n = 0;
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) n += std::abs(img.at(*albedo, x, y)[0] - 0.7f) > 0.01f;
    return n;
}

TEST(GltfMaterials, AUvTransformIsKhrTextureTransformsMatrix) {
    // Image space: s = u, t = 1 - v; (s', t') = offset + R (scale s, scale t), R's rows (cos, sin), (-sin, cos).
    UvTransform t;
    EXPECT_EQ(t.apply({0.3f, 0.8f}), (Vec2{0.3f, 0.8f}));
    std::string why;
    ASSERT_TRUE(make_uv_transform({0.5f, 0.25f}, 0, {2, 4}, t, why));
    const Vec2 a = t.apply({0.25f, 0.75f});  // s = 0.25, t = 0.25 -> (0.5 + 0.5, 0.25 + 1)
    EXPECT_FLOAT_EQ(a.x, 1.0f);
    EXPECT_FLOAT_EQ(a.y, 1 - 1.25f);
    ASSERT_TRUE(make_uv_transform({0, 0}, std::numbers::pi_v<float> / 2, {1, 1}, t, why));
    const Vec2 b = t.apply({1, 1});  // s = 1, t = 0 -> (cos, -sin) = (0, -1)
    EXPECT_NEAR(b.x, 0, 1e-6);
    EXPECT_NEAR(b.y, 2, 1e-6);
    EXPECT_FALSE(make_uv_transform({0, 0}, 0, {0, 1}, t, why));
    EXPECT_FALSE(make_uv_transform({NAN, 0}, 0, {1, 1}, t, why));
    EXPECT_FALSE(make_uv_transform({0, 0}, std::numeric_limits<float>::infinity(), {1, 1}, t, why));
}

// KHR_texture_transform and a base colour factor times its texture, as the scene file's
// uv_transform and color.
TEST(GltfMaterials, ATextureTransformIsTheSceneFilesUvTransform) {
    test::TempDir dir;
    write_stripes(dir.file("leaf.png"));
    const json xf = {{"offset", {0.25, -0.5}}, {"rotation", 0.3}, {"scale", {2, 1.5}}};
    const json m = {{"pbrMetallicRoughness",
                     {{"baseColorTexture", {{"index", 0}, {"extensions", {{"KHR_texture_transform", xf}}}}},
                      {"baseColorFactor", {0.5, 0.8, 1, 1}},
                      {"metallicFactor", 0},
                      {"roughnessFactor", 1}}}};
    const json same = {
        {"color", {0.5, 0.8, 1}}, {"color_texture", dir.file("leaf.png")}, {"specular", 0.04}, {"roughness", 1}, {"uv_transform", xf}};
    const Image a = render_with(stage(card_from(gltf_card(dir, m)), kLeaf), "brute");
    const Image b = render_with(stage(kWrittenCard, same), "brute");
    EXPECT_EQ(test::differing_values(a, b), 0u);
    EXPECT_GT(card_pixels(a), 30u);
    json untransformed = same;
    untransformed.erase("uv_transform");
    const Image c = render_with(stage(kWrittenCard, untransformed), "brute");
    EXPECT_GT(test::differing_values(a, c), 50u);  // not vacuous: the transform moves the stripes
    const Scene s = test::scene_from(stage(card_from(dir.file("card.gltf")), kLeaf));
    EXPECT_TRUE(s.unread.empty()) << s.unread.front();
}

// An MTL's map_Kd replaces its Kd (Blender's importer reads it so); glTF's factor multiplies.
TEST(GltfMaterials, AnMtlTextureReplacesKdWhereAGltfFactorMultiplies) {
    test::TempDir dir;
    write_stripes(dir.file("leaf.png"));
    dir.write("card.mtl", "newmtl a\nKd 0.5 0.5 0.5\nmap_Kd leaf.png\n");
    const std::string obj =
        dir.write("card.obj", "mtllib card.mtl\nv -1 0.2 0\nv 1 0.2 0\nv 1 2.2 0\nvt 0 0\nvt 1 0\nvt 1 1\nusemtl a\nf 1/1 2/2 3/3\n");
    const Scene s = test::scene_from(stage(card_from(obj), kLeaf));
    const auto it = std::find_if(s.materials.begin(), s.materials.end(), [](const Material& x) { return x.name == "card/a"; });
    ASSERT_NE(it, s.materials.end());
    EXPECT_EQ(it->color, Color(1));
    EXPECT_FALSE(it->color_texture.empty());
    const json m = {
        {"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}, {"baseColorFactor", {0.5, 0.5, 0.5, 1}}, {"metallicFactor", 0}}}};
    const Scene g = test::scene_from(stage(card_from(gltf_card(dir, m)), kLeaf));
    const auto gt = std::find_if(g.materials.begin(), g.materials.end(), [](const Material& x) { return x.name.starts_with("card/"); });
    ASSERT_NE(gt, g.materials.end());
    EXPECT_EQ(gt->color, Color(0.5f));
}

// texCoord 1 reads the second uv set (the card's uvs; its first set reads one texel everywhere).
TEST(GltfMaterials, TexCoordOneReadsTheSecondUvSet) {
    test::TempDir dir;
    write_stripes(dir.file("leaf.png"));
    json m = {
        {"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}, {"texCoord", 1}}}, {"metallicFactor", 0}, {"roughnessFactor", 1}}}};
    const json same = {{"color", 1}, {"color_texture", dir.file("leaf.png")}, {"specular", 0.04}, {"roughness", 1}};
    const Image a = render_with(stage(card_from(gltf_card(dir, m, true)), kLeaf), "brute");
    const Image b = render_with(stage(kWrittenCard, same), "brute");
    EXPECT_EQ(test::differing_values(a, b), 0u);
    m["pbrMetallicRoughness"]["baseColorTexture"].erase("texCoord");
    EXPECT_GT(test::differing_values(b, render_with(stage(card_from(gltf_card(dir, m, true)), kLeaf), "brute")), 50u);
    m["pbrMetallicRoughness"]["baseColorTexture"]["texCoord"] = 1;
    // A second set the mesh does not have is refused, naming the mesh and the material.
    const std::string lacking = gltf_card(dir, m, false);
    test::expect_input_error([&] { test::scene_from(stage(card_from(lacking), kLeaf)); }, {"card.gltf", "texCoord 1", "uv set"});
}

// metallicRoughnessTexture: metalness from blue, roughness from green, each times its factor.
TEST(GltfMaterials, AMetallicRoughnessTextureIsTheSceneFilesAndMetalsHaveNoDiffuse) {
    test::TempDir dir;
    write_png(dir.file("leaf.png"), 4, 1, 3, std::vector<unsigned char>(12, 255));
    // Four texels each of dielectric (blue 0, rough) and metal (blue 255, smooth).
    write_png(dir.file("mr.png"), 8, 1, 3, {0, 255, 0, 0, 255, 0, 0, 255, 0, 0, 255, 0, 0, 60, 255, 0, 60, 255, 0, 60, 255, 0, 60, 255});
    json g = json::parse(test::bytes_of(gltf_card(dir, json::object())));
    g["materials"] = {{{"pbrMetallicRoughness",
                        {{"baseColorTexture", {{"index", 0}}},
                         {"baseColorFactor", {0.9, 0.6, 0.3, 1}},
                         {"metallicRoughnessTexture", {{"index", 1}}},
                         {"metallicFactor", 1},
                         {"roughnessFactor", 0.8}}}}};
    g["images"].push_back({{"uri", "mr.png"}});
    g["textures"].push_back({{"source", 1}});
    const std::string file = dir.write("card.gltf", g.dump());
    const json same = {{"color", {0.9, 0.6, 0.3}},
                       {"color_texture", dir.file("leaf.png")},
                       {"metallic_roughness_texture", dir.file("mr.png")},
                       {"metallic", 1},
                       {"roughness", 0.8}};
    const Image a = render_with(stage(card_from(file), kLeaf), "brute");
    const Image b = render_with(stage(kWrittenCard, same), "brute");
    EXPECT_EQ(test::differing_values(a, b), 0u);
    // The albedo layer: the base colour on the dielectric half, 0 on the metal half.
    const Layer* albedo = a.find("albedo");
    float most = 0, least = 1;
    for (int y = 0; y < a.height; ++y)
        for (int x = 0; x < a.width; ++x) {
            const float* v = a.at(*albedo, x, y);
            if (std::abs(v[0] - 0.7f) < 0.01f) continue;  // the wall and floor
            most = std::max(most, v[0]), least = std::min(least, v[0]);
        }
    EXPECT_NEAR(most, 0.9f, 0.01);  // (pixels straddling the halves blend them)
    EXPECT_LT(least, 0.01);
    // Hostile: "metallic" without the texture, or beside a specular colour.
    test::expect_input_error(
        [&] {
            test::scene_from(stage(kWrittenCard, {{"metallic", 0.5}}));
        },
        {"/materials/leaf/metallic", "metallic_roughness_texture"});
    json both = same;
    both["specular"] = 0.5;
    test::expect_input_error([&] { test::scene_from(stage(kWrittenCard, both)); }, {"/materials/leaf/specular"});
}

// emissiveTexture: the camera sees it, and it lights the floor as the same texture on a quad
// light does (the mesh light samples triangles, the quad its rectangle: equal within noise).
TEST(GltfMaterials, AnEmissiveTextureLightsTheSceneAsATexturedQuadLight) {
    test::TempDir dir;
    write_png(dir.file("leaf.png"), 4, 1, 3, std::vector<unsigned char>(12, 255));
    // Bright on the left half, dark on the right: constant along v (the quad light's texture
    // runs down from its top, the mesh's up from its bottom).
    write_png(dir.file("glow.png"), 8, 1, 3,
              {255, 255, 255, 255, 255, 255, 255, 255, 255, 255, 255, 255, 51, 51, 51, 51, 51, 51, 51, 51, 51, 51, 51, 51});
    json g = json::parse(test::bytes_of(gltf_card(dir, json::object())));
    g["materials"] = {{{"emissiveFactor", {1, 1, 1}},
                       {"emissiveTexture", {{"index", 1}}},
                       {"extensions", {{"KHR_materials_emissive_strength", {{"emissiveStrength", 3}}}}},
                       {"pbrMetallicRoughness", {{"baseColorFactor", {0, 0, 0, 1}}, {"metallicFactor", 0}}}}};
    g["images"].push_back({{"uri", "glow.png"}});
    g["textures"].push_back({{"source", 1}});
    const std::string file = dir.write("card.gltf", g.dump());
    // Lit by the card alone: the scene's quad light is taken away.
    auto lit_by_card = [&](const json& card, const json& leaf) {
        json j = stage(card, leaf);
        j["lights"] = json::array();
        return j;
    };
    const json same = {{"color", 0}, {"emission", 3}, {"emission_texture", dir.file("glow.png")}, {"specular", 0.04}, {"roughness", 1}};
    const Image a = render_with(lit_by_card(card_from(file), kLeaf), "none", {Override("render.light_samples=64")});
    const Image b = render_with(lit_by_card(kWrittenCard, same), "none", {Override("render.light_samples=64")});
    EXPECT_EQ(test::differing_values(a, b), 0u);
    // The same radiance as a textured quad light over the card (its front, counter-clockwise,
    // faces +z: both light the floor and the wall behind it).
    json quad_lit = stage(json::array(), kLeaf);
    quad_lit["lights"] = {{{"type", "quad"},
                           {"corner", {-1, 0.2, 0}},
                           {"edge_u", {2, 0, 0}},
                           {"edge_v", {0, 2, 0}},
                           {"color", 3},
                           {"texture", dir.file("glow.png")}}};
    const Image c = render_with(quad_lit, "none", {Override("render.light_samples=64")});
    const Layer *da = a.find("direct"), *dc = c.find("direct"), *albedo = a.find("albedo");
    double sa = 0, sc = 0;
    for (int y = 0; y < a.height; ++y)
        for (int x = 0; x < a.width; ++x)
            if (std::abs(a.at(*albedo, x, y)[0] - 0.7f) < 0.01f)  // the floor and wall, seen past the card in both
                sa += a.at(*da, x, y)[1], sc += c.at(*dc, x, y)[1];
    ASSERT_GT(sc, 0);
    EXPECT_NEAR(sa / sc, 1, 0.03);
    // The camera sees the texture: its bright and dark halves, 3 and 0.6.
    const Layer* beauty = a.find("beauty");
    float most = 0;
    for (int y = 0; y < a.height; ++y)
        for (int x = 0; x < a.width; ++x) most = std::max(most, a.at(*beauty, x, y)[0]);
    EXPECT_NEAR(most, 3, 0.05);
}

// KHR_materials_transmission and KHR_materials_ior onto bounce's glass (the base colour tints
// what passes), doubleSided read as Cycles does (both sides render): nothing named as unread.
TEST(GltfMaterials, TransmissionAndIorAreTheSceneFilesGlass) {
    test::TempDir dir;
    write_png(dir.file("leaf.png"), 4, 1, 3, std::vector<unsigned char>(12, 255));
    const json m = {
        {"doubleSided", true},
        {"pbrMetallicRoughness", {{"baseColorFactor", {0.9, 1, 0.8, 1}}, {"metallicFactor", 0}, {"roughnessFactor", 1}}},
        {"extensions", {{"KHR_materials_transmission", {{"transmissionFactor", 0.5}}}, {"KHR_materials_ior", {{"ior", 1.33}}}}}};
    const std::string file = gltf_card(dir, m);
    const json same = {{"color", {0.9, 1, 0.8}}, {"specular", 0.04}, {"roughness", 1}, {"transmission", {0.45, 0.5, 0.4}}, {"ior", 1.33}};
    const Image a = render_with(stage(card_from(file), kLeaf), "brute");
    const Image b = render_with(stage(kWrittenCard, same), "brute");
    EXPECT_EQ(test::differing_values(a, b), 0u);
    json opaque = same;
    opaque.erase("transmission");
    EXPECT_GT(test::differing_values(a, render_with(stage(kWrittenCard, opaque), "brute")), 50u);
    const Scene s = test::scene_from(stage(card_from(file), kLeaf));
    EXPECT_TRUE(s.unread.empty()) << s.unread.front();
    // A one-sided material renders as the two-sided one (the camera sees the card's back here).
    json one_sided = m;
    one_sided["doubleSided"] = false;
    EXPECT_EQ(test::differing_values(a, render_with(stage(card_from(gltf_card(dir, one_sided)), kLeaf), "brute")), 0u);
}

// Every part survives the mesh cache: a hit renders as the parse did.
TEST(GltfMaterials, TheWholeMaterialSurvivesTheMeshCache) {
    test::TempDir dir;
    write_stripes(dir.file("leaf.png"));
    write_png(dir.file("mr.png"), 4, 1, 3, {0, 255, 0, 0, 200, 255, 0, 60, 255, 0, 90, 0});
    json g = json::parse(test::bytes_of(gltf_card(dir, json::object(), true)));
    g["materials"] = {
        {{"pbrMetallicRoughness",
          {{"baseColorTexture", {{"index", 0}, {"texCoord", 1}, {"extensions", {{"KHR_texture_transform", {{"rotation", 0.4}}}}}}},
           {"metallicRoughnessTexture",
            {{"index", 1}, {"texCoord", 1}, {"extensions", {{"KHR_texture_transform", {{"rotation", 0.4}}}}}}}}},
         {"emissiveFactor", {0.2, 0.1, 0}},
         {"emissiveTexture", {{"index", 0}, {"texCoord", 1}, {"extensions", {{"KHR_texture_transform", {{"rotation", 0.4}}}}}}}}};
    g["images"].push_back({{"uri", "mr.png"}});
    g["textures"].push_back({{"source", 1}});
    const std::string file = dir.write("card.gltf", g.dump());
    const json scene = stage(card_from(file), kLeaf);
    const Image parsed = render_with(scene, "brute");
    setenv("BOUNCE_MESH_CACHE", dir.file("meshes").c_str(), 1);
    const MeshCacheCounts before = mesh_cache_counts();
    const Image miss = render_with(scene, "brute"), hit = render_with(scene, "brute");
    const Scene s = test::scene_from(scene);
    unsetenv("BOUNCE_MESH_CACHE");
    EXPECT_EQ(mesh_cache_counts().hits, before.hits + 2);
    EXPECT_EQ(test::differing_values(parsed, miss), 0u);
    EXPECT_EQ(test::differing_values(parsed, hit), 0u);
    const auto it = std::find_if(s.materials.begin(), s.materials.end(), [](const Material& x) { return x.name.starts_with("card/"); });
    ASSERT_NE(it, s.materials.end());
    EXPECT_EQ(it->uv_set, 1);
    EXPECT_FLOAT_EQ(it->uv_transform.rotation, 0.4f);
    ASSERT_TRUE(it->emission_map);
    EXPECT_FALSE(it->metallic_roughness_texture.empty());
}

/// The card of gltf_card with COLOR_0 `colors` (its four vertices: left bottom, right bottom,
/// right top, left top), as a second inline buffer.
std::string card_with_colors(const test::TempDir& dir, const json& material, const std::vector<float>& colors) {
    json g = json::parse(test::bytes_of(gltf_card(dir, material)));
    std::string b;
    for (float c : colors) test::put<float>(b, {c});
    g["buffers"].push_back({{"byteLength", b.size()}, {"uri", "data:application/octet-stream;base64," + test::base64(b)}});
    g["bufferViews"].push_back({{"buffer", 1}, {"byteOffset", 0}, {"byteLength", b.size()}});
    g["accessors"].push_back(
        {{"bufferView", g["bufferViews"].size() - 1}, {"componentType", 5126}, {"count", colors.size() / 3}, {"type", "VEC3"}});
    g["meshes"][0]["primitives"][0]["attributes"]["COLOR_0"] = g["accessors"].size() - 1;
    return dir.write("card.gltf", g.dump());
}

// COLOR_0 multiplies the base colour for the camera and for the bounce light: equal colours are
// the scene file's colour bit for bit, a gradient runs across the card.
TEST(GltfMaterials, VertexColoursMultiplyTheBaseColour) {
    test::TempDir dir;
    write_stripes(dir.file("leaf.png"));
    const json m = {{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}, {"metallicFactor", 0}, {"roughnessFactor", 1}}}};
    const std::vector<float> tint = {0.5f, 0.25f, 1, 0.5f, 0.25f, 1, 0.5f, 0.25f, 1, 0.5f, 0.25f, 1};
    const json same = {{"color", {0.5, 0.25, 1}}, {"color_texture", dir.file("leaf.png")}, {"specular", 0.04}, {"roughness", 1}};
    const json scene = stage(card_from(card_with_colors(dir, m, tint)), kLeaf);
    const Image a = render_with(scene, "brute"), b = render_with(stage(kWrittenCard, same), "brute");
    EXPECT_EQ(test::differing_values(a, b), 0u);
    json white = same;
    white["color"] = 1;
    EXPECT_GT(test::differing_values(a, render_with(stage(kWrittenCard, white), "brute")), 50u);
    // Through the radiosity textures (the bounce light's other path) and the mesh cache.
    EXPECT_EQ(test::differing_values(render_with(scene, "cache", {Override("render.radiosity=true")}),
                                     render_with(stage(kWrittenCard, same), "cache", {Override("render.radiosity=true")})),
              0u);
    setenv("BOUNCE_MESH_CACHE", dir.file("meshes").c_str(), 1);
    const Image stored = render_with(scene, "brute"), cached = render_with(scene, "brute");
    unsetenv("BOUNCE_MESH_CACHE");
    EXPECT_EQ(test::differing_values(a, cached), 0u);
    // White on the left edge, black on the right: the albedo falls across the card.
    const json plain = {{"pbrMetallicRoughness", {{"metallicFactor", 0}, {"roughnessFactor", 1}}}};
    const Image g = render_with(stage(card_from(card_with_colors(dir, plain, {1, 1, 1, 0, 0, 0, 0, 0, 0, 1, 1, 1})), kLeaf), "none");
    const Layer* albedo = g.find("albedo");
    const int y = g.height / 2;
    std::vector<float> row;
    for (int x = 0; x < g.width; ++x)
        if (const float v = g.at(*albedo, x, y)[1]; std::abs(v - 0.7f) > 1e-3f) row.push_back(v);  // the card, not the wall
    ASSERT_GT(row.size(), 8u);
    row = std::vector<float>(row.begin() + 1, row.end() - 1);            // the edge pixels blend the card with the wall
    if (row.front() < row.back()) std::reverse(row.begin(), row.end());  // from the white edge, however the camera sees it
    EXPECT_GT(row.front(), 0.85f);
    EXPECT_LT(row.back(), 0.15f);
    for (size_t i = 1; i < row.size(); ++i) EXPECT_LE(row[i], row[i - 1] + 1e-6f) << i;
    const Scene s = test::scene_from(stage(card_from(dir.file("card.gltf")), kLeaf));
    EXPECT_TRUE(s.unread.empty()) << s.unread.front();
    // A subdivision surface does not carry them: said, not dropped in silence.
    // (Beside what its materials leave unread: that line once did hide theirs.)
    json sheen = plain;
    sheen["extensions"] = {{"KHR_materials_sheen", json::object()}};
    json subdivided = card_from(card_with_colors(dir, sheen, {1, 1, 1, 0, 0, 0, 0, 0, 0, 1, 1, 1}));
    subdivided[0]["subdivision"] = "loop";
    const Scene d = test::scene_from(stage(subdivided, kLeaf));
    ASSERT_EQ(d.unread.size(), 2u);
    EXPECT_EQ(d.unread[0], dir.file("card.gltf") + ": ignored: COLOR_0 (vertex colours) on a subdivision surface");
    EXPECT_EQ(d.unread[1], dir.file("card.gltf") + ": ignored: KHR_materials_sheen on 1 material");
    // Hostile: a count other than the vertices', a component outside [0, 1].
    const std::string three = card_with_colors(dir, plain, {1, 1, 1, 0, 0, 0, 0, 0, 0});
    test::expect_input_error([&] { test::scene_from(stage(card_from(three), kLeaf)); },
                             {"card.gltf", "attributes/COLOR_0", "3 elements", "4 vertices"});
    const std::string bright = card_with_colors(dir, plain, {1, 1, 1, 0, 0, 0, 0, 2, 0, 1, 1, 1});
    test::expect_input_error([&] { test::scene_from(stage(card_from(bright), kLeaf)); },
                             {"card.gltf", "COLOR_0", "2 is not a colour component"});
}

// Images inside the file (data: URIs here, a .glb's buffer views alike) are read as the same
// images beside it: written once to the image cache, by content.
TEST(GltfMaterials, EmbeddedImagesAreTheSameImagesAsFiles) {
    test::TempDir dir;
    write_stripes(dir.file("leaf.png"));
    setenv("BOUNCE_IMAGE_CACHE", dir.file("images").c_str(), 1);
    const json m = {{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}, {"metallicFactor", 0}, {"roughnessFactor", 1}}}};
    const Image beside = render_with(stage(card_from(gltf_card(dir, m)), kLeaf), "brute");
    json g = json::parse(test::bytes_of(dir.file("card.gltf")));
    g["images"][0] = {{"uri", "data:image/png;base64," + test::base64(test::bytes_of(dir.file("leaf.png")))}};
    const std::string inside = dir.write("inside.gltf", g.dump());
    const Image embedded = render_with(stage(card_from(inside), kLeaf), "brute");
    EXPECT_EQ(test::differing_values(beside, embedded), 0u);
    size_t written = 0;
    for (const auto& e : std::filesystem::directory_iterator(dir.file("images"))) written += e.path().extension() == ".png";
    EXPECT_EQ(written, 1u);
    // Again, and through the mesh cache: the same file, nothing more written.
    setenv("BOUNCE_MESH_CACHE", dir.file("meshes").c_str(), 1);
    const Image stored = render_with(stage(card_from(inside), kLeaf), "brute"),
                cached = render_with(stage(card_from(inside), kLeaf), "brute");
    unsetenv("BOUNCE_MESH_CACHE");
    EXPECT_EQ(test::differing_values(beside, cached), 0u);
    EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.file("images")), {}), 1);
    // Bytes that are no image are refused naming the material, an image cache that cannot be
    // written too.
    g["images"][0] = {{"uri", "data:image/png;base64," + test::base64("not an image at all")}};
    const std::string broken = dir.write("inside.gltf", g.dump());
    test::expect_input_error([&] { test::scene_from(stage(card_from(broken), kLeaf)); }, {"inside.gltf", "material"});
    setenv("BOUNCE_IMAGE_CACHE", dir.write("a-file", "x").c_str(), 1);
    g["images"][0] = {{"uri", "data:image/png;base64," + test::base64(test::bytes_of(dir.file("leaf.png")) + " ")}};
    const std::string elsewhere = dir.write("inside.gltf", g.dump());
    test::expect_input_error([&] { test::scene_from(stage(card_from(elsewhere), kLeaf)); }, {"inside.gltf", "BOUNCE_IMAGE_CACHE"});
    unsetenv("BOUNCE_IMAGE_CACHE");
}

TEST(GltfMaterials, WhatIsNotReadIsNamedAndHostileValuesAreRefused) {
    test::TempDir dir;
    write_png(dir.file("leaf.png"), 4, 1, 3, std::vector<unsigned char>(12, 255));
    json m = {
        {"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}, {"metallicRoughnessTexture", {{"index", 0}, {"texCoord", 1}}}}},
        {"extensions", {{"KHR_materials_sheen", json::object()}}}};
    Scene s = test::scene_from(stage(card_from(gltf_card(dir, m, true)), kLeaf));
    ASSERT_EQ(s.unread.size(), 2u);
    EXPECT_NE(s.unread[0].find("metallicRoughnessTexture on another uv set or transform"), std::string::npos) << s.unread[0];
    EXPECT_NE(s.unread[1].find("KHR_materials_sheen on 1 material"), std::string::npos) << s.unread[1];
    // ... and not read at the wrong uvs: the material keeps the factors alone.
    const auto it = std::find_if(s.materials.begin(), s.materials.end(), [](const Material& x) { return x.name.starts_with("card/"); });
    ASSERT_NE(it, s.materials.end());
    EXPECT_TRUE(it->metallic_roughness_texture.empty());
    EXPECT_FALSE(it->color_texture.empty());
    // Values out of range, each named by its JSON pointer.
    const auto refused = [&](const std::string& text, const std::vector<std::string>& parts) {
        json g = json::parse(test::bytes_of(gltf_card(dir, json::object())));
        std::string doc = g.dump();
        doc.replace(doc.find("\"materials\":[{}]"), 16, "\"materials\":[" + text + "]");
        const std::string file = dir.write("card.gltf", doc);
        test::expect_input_error([&] { test::scene_from(stage(card_from(file), kLeaf)); }, parts);
    };
    const std::string base = R"("pbrMetallicRoughness":{"baseColorTexture":{"index":0,)";
    refused("{" + base + R"("extensions":{"KHR_texture_transform":{"rotation":1e39}}}}})",
            {"card.gltf", "KHR_texture_transform", "rotation"});
    refused("{" + base + R"("extensions":{"KHR_texture_transform":{"offset":[null,0]}}}}})",
            {"card.gltf", "KHR_texture_transform/offset/0"});
    refused("{" + base + R"("extensions":{"KHR_texture_transform":{"scale":[0,1]}}}}})",
            {"card.gltf", "KHR_texture_transform", "scale of 0"});
    refused("{" + base + R"("texCoord":5}}})", {"card.gltf", "baseColorTexture/texCoord"});
    refused(R"({"extensions":{"KHR_materials_ior":{"ior":10}}})", {"card.gltf", "KHR_materials_ior/ior"});
    refused(R"({"extensions":{"KHR_materials_transmission":{"transmissionFactor":2}}})", {"card.gltf", "transmissionFactor"});
    // An emission texture that is not there, or too large to read whole.
    {
        json g = json::parse(test::bytes_of(gltf_card(dir, json::object())));
        g["materials"] = {{{"emissiveFactor", {1, 1, 1}}, {"emissiveTexture", {{"index", 1}}}}};
        g["images"].push_back({{"uri", "none.png"}});
        g["textures"].push_back({{"source", 1}});
        const std::string file = dir.write("card.gltf", g.dump());
        test::expect_input_error([&] { test::scene_from(stage(card_from(file), kLeaf)); }, {"card.gltf", "none.png"});
    }
    test::expect_input_error(
        [&] {
            test::scene_from(stage(kWrittenCard, {{"emission_texture", dir.file("none.png")}}));
        },
        {"/materials/leaf/emission_texture", "none.png"});
    const std::string huge = write_huge_png(dir);
    test::expect_input_error(
        [&] {
            test::scene_from(stage(kWrittenCard, {{"emission_texture", huge}}));
        },
        {"/materials/leaf/emission_texture", "30000x30000", "8192x8192"});
    test::expect_input_error(
        [&] {
            test::scene_from(stage(kWrittenCard, {{"uv_transform", {{"scale", {1, 0}}}}}));
        },
        {"/materials/leaf/uv_transform", "scale of 0"});
    test::expect_input_error(
        [&] {
            test::scene_from(stage(kWrittenCard, {{"uv_transform", {{"offset", {1, 2, 3}}}}}));
        },
        {"/materials/leaf/uv_transform/offset"});
}

}  // namespace
}  // namespace bounce
