// Scene loading: the JSON format, overrides, glTF files with their camera and lights, and
// every kind of bad input (one clear error naming the file and the place).
#include <gtest/gtest.h>

#include <cstring>

#include "bounce/core/error.h"
#include "bounce/scene/json_reader.h"
#include "bounce/scene/mesh_import.h"
#include "test_util.h"

namespace bounce {
namespace {

using nlohmann::json;
using test::base_scene;
using test::scene_from;

using test::expect_input_error;

TEST(SceneLoad, CornellSceneHasItsMeasuredContent) {
    Scene s = load_scene(test::cornell_scene());
    EXPECT_EQ(s.objects.size(), 8u);
    EXPECT_EQ(s.camera.width, 512);
    EXPECT_NEAR(s.camera.fov, 39.3077f, 1e-4f);
    ASSERT_EQ(s.lights.size(), 1u);  // the emissive light quad
    EXPECT_EQ(s.lights[0].type, LightType::Mesh);
    Bounds b = s.bounds();
    EXPECT_NEAR(b.hi.x, 556.0f, 1e-3f);
    EXPECT_NEAR(b.hi.z, 559.2f, 1e-3f);
    size_t tris = 0;
    for (const auto& o : s.objects) tris += o.coarse.triangle_count();
    EXPECT_EQ(tris, 6u * 2 + 2 * 5 * 2);
}

TEST(SceneLoad, OverridesSetAnyValueByPath) {
    json j = base_scene();
    j["lights"] = {{{"type", "point"}, {"position", {0, 1, 0}}}};
    Scene s = scene_from(j, {"camera.fov=60", "lights.0.color=[1,2,3]", "render.spp=7", "camera.resolution=[20,10]"});
    EXPECT_EQ(s.camera.fov, 60.0f);
    EXPECT_EQ(s.lights[0].color, Color(1, 2, 3));
    EXPECT_EQ(s.render.visibility.spp, 7);
    EXPECT_EQ(s.camera.width, 20);
    EXPECT_EQ(s.camera.height, 10);
}

TEST(SceneLoad, TransformsApplyTranslateRotateScale) {
    json j = base_scene();
    j["objects"] = {{{"type", "quad"},
                     {"vertices", {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}},
                     {"transform", {{"translate", {10, 0, 0}}, {"rotate", {90, 0, 0, 1}}, {"scale", 2}}}}};
    Scene s = scene_from(j);
    Vec3 p = s.objects[0].coarse.positions[1];  // (1,0,0) -> scale (2,0,0) -> rotate (0,2,0) -> (10,2,0)
    EXPECT_NEAR(p.x, 10, 1e-5f);
    EXPECT_NEAR(p.y, 2, 1e-5f);
}

TEST(SceneLoad, MissingFile) {
    expect_input_error([] { load_scene("/nonexistent/scene.json"); }, {"/nonexistent/scene.json", "not found"});
}

TEST(SceneLoad, MalformedJsonReportsLineAndColumn) {
    std::string text = "{\n  \"camera\": {\n    \"fov\": 40,,\n  }\n}\n";
    expect_input_error([&] { load_scene_text(text, "bad.json"); }, {"bad.json: 3:", "malformed JSON"});
}

TEST(SceneLoad, TheParserBuildsNlohmannsDocumentAndNamesADuplicateKeyWhereverItIs) {
    const std::string cornell = test::bytes_of(test::cornell_scene());
    EXPECT_EQ(parse_json_text(cornell, "c.json"), json::parse(cornell));
    const std::string mixed = R"({"a": [1, -2, 3.5e300, true, null, "s", [], {}, [[{"b": {"c": [0]}}]]], "u": 18446744073709551615})";
    EXPECT_EQ(parse_json_text(mixed, "m.json"), json::parse(mixed));
    auto refused = [](const std::string& text, const std::string& pointer) {
        expect_input_error([&] { parse_json_text(text, "d.json"); }, {"d.json: " + pointer + ": error: key given twice in one object"});
    };
    refused(R"({"a": 1, "a": 2})", "/a");
    refused(R"({"objects": [{"name": "x"}, {"type": "quad", "name": "y", "type": "mesh"}]})", "/objects/1/type");
    refused(R"({"o": [[0], [1, {"k": {"x": 1, "y": [{"z": 0, "z": 1}]}}]]})", "/o/1/1/k/y/0/z");
    // The first duplicate is named, and keys of the same name in other objects are not duplicates.
    refused(R"({"p": {"q": 1}, "q": {"q": 2, "r": 3, "r": 4}, "s": {"t": 0, "t": 0}})", "/q/r");
    expect_input_error([] { parse_json_text("[1, 2", "t.json"); }, {"t.json: 1:", "malformed JSON"});
}

TEST(SceneLoad, UnknownKeySuggestsTheClosest) {
    json j = base_scene();
    j["lights"] = {{{"type", "point"}, {"position", {0, 1, 0}}, {"intensty", 3}}};
    expect_input_error([&] { scene_from(j); }, {"inline.json", "/lights/0/intensty", "did you mean \"intensity\""});
    json k = base_scene();
    k["camera"]["look_at_point"] = {0, 0, 0};
    expect_input_error([&] { scene_from(k); }, {"/camera/look_at_point", "unknown key"});
}

TEST(SceneLoad, UnknownEnumListsValidValues) {
    json j = base_scene();
    j["lights"] = {{{"type", "pointy"}}};
    expect_input_error([&] { scene_from(j); }, {"/lights/0/type", "pointy", "point, spot, distant, quad, sky"});
}

TEST(SceneLoad, WrongTypes) {
    json j = base_scene();
    j["camera"]["fov"] = "wide";
    expect_input_error([&] { scene_from(j); }, {"/camera/fov", "expected a number, got a string"});
    json k = base_scene();
    k["camera"]["position"] = {0, 1};
    expect_input_error([&] { scene_from(k); }, {"/camera/position", "3 numbers"});
    json m = base_scene();
    m["render"] = {{"spp", 2.5}};
    expect_input_error([&] { scene_from(m); }, {"/render/spp", "integer"});
}

TEST(SceneLoad, NonFiniteAndNegativeSizes) {
    json j = base_scene();
    expect_input_error([&] { scene_from(j, {"camera.fov=NaN"}); }, {"command line", "/camera/fov", "expected a number"});
    expect_input_error([&] { scene_from(j, {"camera.fov=1e999"}); }, {"/camera/fov", "not finite"});
    expect_input_error([&] { scene_from(j, {"camera.resolution=[-5,10]"}); }, {"/camera/resolution/0", "out of range"});
    expect_input_error([&] { scene_from(j, {"camera.fov=180"}); }, {"/camera/fov"});
    json s = base_scene();
    s["objects"] = {{{"type", "sphere"}, {"radius", -1}}};
    expect_input_error([&] { scene_from(s); }, {"/objects/0/radius", "out of range"});
    json c = base_scene();
    c["materials"] = {{"m", {{"color", {0.5, -0.1, 0.2}}}}};
    expect_input_error([&] { scene_from(c); }, {"/materials/m/color/1", ">= 0"});
}

TEST(SceneLoad, BadOverrideSyntax) {
    json j = base_scene();
    expect_input_error([&] { scene_from(j, {"camera.fov"}); }, {"command line", "key=value"});
    expect_input_error([&] { scene_from(j, {"objects.5.type=quad"}); }, {"command line", "out of range"});
}

TEST(SceneLoad, UnknownMaterialSuggestsTheClosest) {
    json j = base_scene();
    j["materials"] = {{"white", json::object()}};
    j["objects"][0]["material"] = "whte";
    expect_input_error([&] { scene_from(j); }, {"/objects/0/material", "did you mean \"white\""});
}

TEST(SceneLoad, EmptyAndMissingMeshes) {
    test::TempDir d;
    d.write("empty.obj", "# nothing but vertices\nv 0 0 0\nv 1 0 0\nv 0 1 0\n");
    json j = base_scene();
    j["objects"] = {{{"file", "empty.obj"}}};
    std::string path = d.write("scene.json", j.dump());
    expect_input_error([&] { load_scene(path); }, {"scene.json", "/objects/0/file", "empty.obj"});
    j["objects"] = {{{"file", "missing.obj"}}};
    path = d.write("scene.json", j.dump());
    expect_input_error([&] { load_scene(path); }, {"/objects/0/file", "file not found", "missing.obj"});
    j["objects"] = json::array();
    path = d.write("scene.json", j.dump());
    expect_input_error([&] { load_scene(path); }, {"/objects", "non-empty"});
}

TEST(SceneLoad, MeshFileMaterialsAndOverride) {
    // McGuire's Cornell box OBJ+MTL, shipped in tests/data.
    std::string obj = test::source_dir() + "/tests/data/cornell_box/CornellBox-Original.obj";
    std::vector<Material> mats;
    TriangleMesh m = load_mesh_file(obj, "box", mats, -1);
    EXPECT_EQ(m.triangle_count(), 36u);
    bool red = false, light = false;
    for (const auto& mat : mats) {
        red |= std::abs(mat.color.x - 0.63f) < 1e-4f && std::abs(mat.color.y - 0.065f) < 1e-4f;
        light |= mat.emission == Color(17, 12, 4);
    }
    EXPECT_TRUE(red);
    EXPECT_TRUE(light);
    std::vector<Material> none;
    TriangleMesh o = load_mesh_file(obj, "box", none, 3);
    EXPECT_TRUE(none.empty());
    for (uint32_t f : o.face_materials) EXPECT_EQ(f, 3u);
}

std::string base64(const std::string& in) {
    static const char* tbl = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    size_t i = 0;
    for (; i + 2 < in.size(); i += 3) {
        uint32_t v = (uint8_t(in[i]) << 16) | (uint8_t(in[i + 1]) << 8) | uint8_t(in[i + 2]);
        for (int k = 3; k >= 0; --k) out += tbl[(v >> (6 * k)) & 63];
    }
    if (i + 1 == in.size()) {
        uint32_t v = uint8_t(in[i]) << 16;
        out += tbl[(v >> 18) & 63], out += tbl[(v >> 12) & 63], out += "==";
    } else if (i + 2 == in.size()) {
        uint32_t v = (uint8_t(in[i]) << 16) | (uint8_t(in[i + 1]) << 8);
        out += tbl[(v >> 18) & 63], out += tbl[(v >> 12) & 63], out += tbl[(v >> 6) & 63], out += "=";
    }
    return out;
}

/// A glTF 2.0 file: a 4x4 quad at z = 0, a camera at z = 5 (yfov 0.8, aspect 1.5) and a point
/// light at z = 2 (KHR_lights_punctual).
std::string write_gltf(const test::TempDir& d) {
    float pos[12] = {-2, -2, 0, 2, -2, 0, 2, 2, 0, -2, 2, 0};
    uint16_t idx[6] = {0, 1, 2, 0, 2, 3};
    std::string buf(60, '\0');
    std::memcpy(buf.data(), pos, 48);
    std::memcpy(buf.data() + 48, idx, 12);
    json g = {
        {"asset", {{"version", "2.0"}}},
        {"extensionsUsed", {"KHR_lights_punctual"}},
        {"extensions", {{"KHR_lights_punctual", {{"lights", {{{"type", "point"}, {"color", {1, 0.5, 0.25}}, {"intensity", 10}}}}}}}},
        {"scene", 0},
        {"scenes", {{{"nodes", {0, 1, 2}}}}},
        {"nodes",
         {{{"mesh", 0}},
          {{"camera", 0}, {"translation", {0, 0, 5}}},
          {{"extensions", {{"KHR_lights_punctual", {{"light", 0}}}}}, {"translation", {0, 0, 2}}}}},
        {"cameras", {{{"type", "perspective"}, {"perspective", {{"yfov", 0.8}, {"aspectRatio", 1.5}, {"znear", 0.1}}}}}},
        {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}}}, {"indices", 1}, {"material", 0}}}}}}},
        {"materials",
         {{{"pbrMetallicRoughness", {{"baseColorFactor", {0.5, 0.6, 0.7, 1}}, {"metallicFactor", 0.25}, {"roughnessFactor", 0.3}}}}}},
        {"buffers", {{{"byteLength", 60}, {"uri", "data:application/octet-stream;base64," + base64(buf)}}}},
        {"bufferViews", {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 48}}, {{"buffer", 0}, {"byteOffset", 48}, {"byteLength", 12}}}},
        {"accessors",
         {{{"bufferView", 0}, {"componentType", 5126}, {"count", 4}, {"type", "VEC3"}, {"min", {-2, -2, 0}}, {"max", {2, 2, 0}}},
          {{"bufferView", 1}, {"componentType", 5123}, {"count", 6}, {"type", "SCALAR"}}}}};
    return d.write("quad.gltf", g.dump());
}

TEST(SceneLoad, GltfWithCameraAndPunctualLights) {
    test::TempDir d;
    Scene s = load_scene(write_gltf(d));
    EXPECT_NEAR(s.camera.position.z, 5.0f, 1e-5f);
    EXPECT_NEAR(s.camera.look_at.z, 4.0f, 1e-5f);  // looks down -Z
    EXPECT_NEAR(s.camera.fov, 0.8f * 180 / kPi, 1e-3f);
    EXPECT_EQ(s.camera.width, 640);
    EXPECT_EQ(s.camera.height, 427);
    ASSERT_EQ(s.lights.size(), 1u);
    EXPECT_EQ(s.lights[0].type, LightType::Point);
    EXPECT_NEAR(s.lights[0].position.z, 2.0f, 1e-5f);
    EXPECT_EQ(s.lights[0].color, Color(10, 5, 2.5f));  // colour x intensity
    ASSERT_EQ(s.objects.size(), 1u);
    EXPECT_EQ(s.objects[0].coarse.triangle_count(), 2u);
    // Metallic-roughness: diffuse = base (1 - metallic), F0 = mix(0.04, base, metallic).
    const Material& m = s.materials[s.objects[0].coarse.face_materials[0]];
    EXPECT_NEAR(m.color.y, 0.6f * 0.75f, 1e-6f);
    EXPECT_NEAR(m.specular.y, 0.04f * 0.75f + 0.6f * 0.25f, 1e-6f);
    EXPECT_NEAR(m.roughness, 0.3f, 1e-6f);
}

TEST(SceneLoad, GltfWithoutCameraIsRefused) {
    test::TempDir d;
    std::string obj = d.write("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    expect_input_error([&] { load_scene(obj); }, {"tri.obj", "no camera"});
}

}  // namespace
}  // namespace bounce
