// Issue 65, hostile inputs round 5: the OpenColorIO config and its LUTs are inputs (no output
// overwrites them; a LUT that is a FIFO is refused before OpenColorIO blocks on it; an empty
// --ocio-config is refused), an OBJ's MTL is checked before anything opens it and a missing one
// is an error, singular glTF placements are refused as the scene file refuses them, and the
// command line's messages say what is wrong.
#include <sys/stat.h>

#include <filesystem>
#include <fstream>

#include "test_util.h"

namespace bounce {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

/// A config whose view reads a 1D LUT (`thelut.cube` beside it, in luts/).
void write_lut_config(const test::TempDir& d) {
    std::string config = test::bytes_of(test::source_dir() + "/tests/data/ocio/config.ocio");
    config.replace(config.find("search_path: \"\""), 15, "search_path: luts");
    config += R"(
  - !<ColorSpace>
    name: lut
    family: ""
    equalitygroup: ""
    bitdepth: 32f
    isdata: false
    from_scene_reference: !<FileTransform> {src: thelut.cube, interpolation: linear}
)";
    config.replace(config.find("    - !<View> {name: raw, colorspace: linear}"), 0, "    - !<View> {name: lut, colorspace: lut}\n");
    d.write("lut.ocio", config);
    fs::create_directories(d.path() / "luts");
    d.write("luts/thelut.cube", "LUT_1D_SIZE 2\n0 0 0\n1 1 1\n");
}

std::string small_render(const test::TempDir& d) {
    d.write("s.json", test::base_scene().dump());
    return "render " + d.file("s.json") + " -q --threads 1 -o " + d.file("o.exr");
}

TEST(HostileColour, OutputsMayNotOverwriteTheConfigOrItsLuts) {
    test::TempDir d;
    write_lut_config(d);
    const std::string config = test::bytes_of(d.file("lut.ocio")), lut = test::bytes_of(d.file("luts/thelut.cube"));
    const std::string base = small_render(d) + " --ocio-config " + d.file("lut.ocio") + " --view lut";
    ASSERT_EQ(test::run_bounce(base), 0);  // the config works
    test::expect_refused(base + " --stats-json " + d.file("lut.ocio"), {"lut.ocio", "output names an input"});
    test::expect_refused(base + " --deep-out " + d.file("lut.ocio"), {"lut.ocio", "output names an input"});
    test::expect_refused(base + " --gi cache --cache-out " + d.file("lut.ocio"), {"lut.ocio", "output names an input"});
    test::expect_refused(base + " --stats-json " + d.file("luts/thelut.cube"), {"thelut.cube", "output names an input"});
    // Through $OCIO as well.
    std::string err;
    EXPECT_EQ(test::run_bounce_shell("OCIO=" + d.file("lut.ocio") + " " + std::string(BOUNCE_BINARY) + " " + small_render(d) +
                                         " --stats-json " + d.file("lut.ocio"),
                                     &err),
              2)
        << err;
    EXPECT_NE(err.find("output names an input"), std::string::npos) << err;
    EXPECT_EQ(test::bytes_of(d.file("lut.ocio")), config);
    EXPECT_EQ(test::bytes_of(d.file("luts/thelut.cube")), lut);
}

TEST(HostileColour, ALutThatIsAFifoIsRefusedBeforeOpenColorIoOpensIt) {
    test::TempDir d;
    write_lut_config(d);
    fs::remove(d.file("luts/thelut.cube"));
    ASSERT_EQ(mkfifo(d.file("luts/thelut.cube").c_str(), 0600), 0);
    // Refused at once (OpenColorIO would block in open() for good: the test would time out).
    test::expect_refused(small_render(d) + " --ocio-config " + d.file("lut.ocio") + " --view lut",
                         {"lut.ocio", "thelut.cube", "not a regular file"});
}

TEST(HostileColour, AnEmptyConfigNameIsRefused) {
    test::TempDir d;
    test::expect_refused(small_render(d) + " --ocio-config ''", {"--ocio-config", "empty file name"});
}

TEST(HostileMesh, AnObjWhoseMtlIsMissingIsRefusedUnlessASceneMaterialReplacesIt) {
    test::TempDir d;
    d.write("t.obj", "mtllib nosuch.mtl\nv 0 0 0\nv 1 0 0\nv 0 0 1\nusemtl x\nf 1 2 3\n");
    json j = test::base_scene();
    j["objects"].push_back({{"name", "t"}, {"type", "mesh"}, {"file", "t.obj"}});
    d.write("s.json", j.dump());
    test::expect_refused("render " + d.file("s.json") + " -q -o " + d.file("o.exr"), {"t.obj", "line 1", "nosuch.mtl"});
    // A scene material in its place: the MTL is not needed.
    j["materials"] = {{"grey", {{"color", {0.5, 0.5, 0.5}}}}};
    j["objects"].back()["material"] = "grey";
    d.write("s.json", j.dump());
    EXPECT_EQ(test::run_bounce("render " + d.file("s.json") + " -q -o " + d.file("o.exr")), 0);
}

/// glTF with one triangle mesh used by two nodes (a shared mesh: placements), embedded buffer.
json shared_mesh_gltf() {
    const float pos[9] = {0, 0, 0, 1, 0, 0, 0, 0, 1};
    std::string bytes(reinterpret_cast<const char*>(pos), sizeof pos);
    std::string b64;
    static const char* tab = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    for (size_t i = 0; i < bytes.size(); i += 3) {
        uint32_t v = static_cast<uint8_t>(bytes[i]) << 16;
        if (i + 1 < bytes.size()) v |= static_cast<uint8_t>(bytes[i + 1]) << 8;
        if (i + 2 < bytes.size()) v |= static_cast<uint8_t>(bytes[i + 2]);
        b64 += tab[(v >> 18) & 63], b64 += tab[(v >> 12) & 63];
        b64 += i + 1 < bytes.size() ? tab[(v >> 6) & 63] : '=';
        b64 += i + 2 < bytes.size() ? tab[v & 63] : '=';
    }
    return {{"asset", {{"version", "2.0"}}},
            {"scene", 0},
            {"scenes", {{{"nodes", {0, 1}}}}},
            {"nodes", {{{"mesh", 0}, {"translation", {0, 0, 0}}}, {{"mesh", 0}, {"translation", {3, 0, 0}}}}},
            {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}}}}}}}}},
            {"accessors",
             {{{"bufferView", 0}, {"componentType", 5126}, {"count", 3}, {"type", "VEC3"}, {"min", {0, 0, 0}}, {"max", {1, 0, 1}}}}},
            {"bufferViews", {{{"buffer", 0}, {"byteLength", 36}}}},
            {"buffers", {{{"byteLength", 36}, {"uri", "data:application/octet-stream;base64," + b64}}}}};
}

TEST(HostileMesh, SingularGltfPlacementsAreRefusedAsTheSceneFileRefusesThem) {
    test::TempDir d;
    const auto render = [&](const json& gltf) {
        d.write("m.gltf", gltf.dump());
        json j = test::base_scene();
        j["objects"].push_back({{"name", "m"}, {"type", "mesh"}, {"file", "m.gltf"}});
        d.write("s.json", j.dump());
        return "render " + d.file("s.json") + " -q -o " + d.file("o.exr");
    };
    ASSERT_EQ(test::run_bounce(render(shared_mesh_gltf())), 0);
    json g = shared_mesh_gltf();
    g["nodes"][1]["scale"] = {0, 0, 0};
    test::expect_refused(render(g), {"m.gltf", "singular"});
    g = shared_mesh_gltf();
    g["nodes"][1].erase("translation");
    g["nodes"][1]["matrix"] = json::array();
    for (int i = 0; i < 16; ++i) g["nodes"][1]["matrix"].push_back(0);
    test::expect_refused(render(g), {"m.gltf", "singular"});
}

TEST(HostileCli, MessagesSayWhatIsWrong) {
    test::TempDir d;
    json j = test::base_scene();
    j["animation"] = {{"fps", 24}, {"frames", {1, 6}}};
    d.write("sh.json", j.dump());
    const std::string shot = "render " + d.file("sh.json") + " -q -o " + d.file("f.####.exr");
    test::expect_refused(shot + " --frames 1-1000000000", {"--frames", "1000000000", "past the largest frame"});
    test::expect_refused(shot + " --frames 5-2", {"--frames", "first frame 5 is after the last 2"});
    const std::string still = small_render(d).substr(0, small_render(d).find(" --threads 1")) + " -o " + d.file("o.exr");
    test::expect_refused(still + " --threads -1", {"--threads", "-1"});
    test::expect_refused(still + " --threads 1 --threads -1", {"--threads", "given more than once"});
    // A folder where an output goes: the reason, not "Success".
    fs::create_directories(d.path() / "o.exr");
    std::string err;
    EXPECT_EQ(test::run_bounce(small_render(d), &err), 2);
    EXPECT_EQ(err.find("Success"), std::string::npos) << err;
}

}  // namespace
}  // namespace bounce
