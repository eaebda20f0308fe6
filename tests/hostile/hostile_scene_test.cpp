// Hostile scene files and values (the scene file, its keys, JSON, numbers out of range, what a
// flag replaces): each refused with one line naming the file and the place, exit status 2.
#include <gtest/gtest.h>

#include "hostile/hostile_util.h"

namespace bounce {
namespace {

using namespace hostile;  // json, fs, expect_refused and the shared scenes

TEST(HostileJson, NestingIsBoundedBeforeAnyParserRecurses) {
    test::TempDir d;
    // 10^6 nested arrays (2 MB) and 2 10^5 nested objects in the description used to segfault.
    std::string arrays = R"({"description": )" + std::string(1000000, '[') + std::string(1000000, ']') + "}";
    d.write("arrays.json", arrays);
    try {
        load_scene(d.file("arrays.json"));
        FAIL();
    } catch (const InputError& e) {
        EXPECT_EQ(e.place(), "1:272");  // the 257th bracket: 15 characters of key, then 256 accepted
        EXPECT_NE(std::string(e.what()).find("nested deeper than 256"), std::string::npos) << e.what();
    }
    std::string objects = R"({"description": )";
    for (int i = 0; i < 200000; ++i) objects += R"({"a":)";
    objects += "1" + std::string(200000, '}') + "}";
    d.write("objects.json", objects);
    EXPECT_THROW(load_scene(d.file("objects.json")), InputError);
    // Brackets inside strings do not count; --set values are bounded too.
    json ok = test::base_scene();
    ok["description"] = std::string(5000, '[');
    EXPECT_NO_THROW(test::scene_from(ok));
    EXPECT_THROW(load_scene(test::cornell_scene(), {Override("camera.fov=" + std::string(300, '[') + std::string(300, ']'))}), InputError);
}

TEST(HostileKeys, KeysAnotherObjectTypeReadsAreErrorsNotIgnored) {
    test::TempDir d;
    const auto refused_object = [&](json object, const std::string& key) {
        json j = test::base_scene();
        j["objects"] = {object};
        d.write("k.json", j.dump());
        test::expect_refused(render_cmd(d.file("k.json"), d.file("o.exr")), {"k.json", "/objects/0/" + key, "does not apply"});
    };
    d.write("grid.obj", "v 0 0 0\nv 1 0 0\nv 1 0 1\nv 0 0 1\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nf 1/1 2/2 3/3 4/4\n");
    write_constant_image(d.file("map.png"), 4, 4, 1, 0.5f);
    refused_object({{"type", "mesh"}, {"file", "grid.obj"}, {"displacement", {{"map", "map.png"}, {"scale", 0.1}}}}, "displacement");
    refused_object({{"type", "mesh"}, {"file", "grid.obj"}, {"boundary", "edge-only"}}, "boundary");
    refused_object({{"type", "sphere"}, {"subdivision", "loop"}}, "subdivision");
    refused_object({{"type", "quad"}, {"vertices", {{0, 0, 0}, {1, 0, 0}, {1, 0, 1}, {0, 0, 1}}}, {"subdivision", "catmull-clark"}},
                   "subdivision");
    // Light keys are checked per type as well.
    json j = test::base_scene();
    j["lights"] = {{{"type", "point"}, {"position", {0, 1, 0}}, {"edge_u", {1, 0, 0}}}};
    d.write("l.json", j.dump());
    test::expect_refused(render_cmd(d.file("l.json"), d.file("o.exr")), {"l.json", "/lights/0/edge_u", "point light"});
}

TEST(HostileValues, CropsFramesDistributionAndHeadersOutOfRange) {
    test::TempDir d;
    const std::string cornell = "render " + test::cornell_scene() + " -q --res 16x16 -o " + d.file("o.exr");
    // An empty crop is not the full frame.
    expect_refused(cornell + " --crop 4,4,4,4", {"/render/crop", "crop [4, 4, 4, 4] is empty"});
    // --distribute: its two values, and frames only with --frames.
    expect_refused(cornell + " --distribute pixels", {"--distribute pixels", "is tiles or frames"});
    expect_refused(cornell + " --distribute frames", {"--distribute frames", "goes with --frames"});
    // A cache whose header's frame is past any frame (1e39 read as -2147483648).
    ASSERT_EQ(test::run_bounce(cornell + " --gi cache --rays 16 --cache-out " + d.file("c.bic")), 0);
    // Rewrite the header with "frame": 1e39 and its checksum, as a crafted file would.
    const std::string bytes = test::bytes_of(d.file("c.bic"));
    const std::string crafted = test::with_cache_header(bytes, [](json& h) { h["frame"] = 1e39; });
    d.write("big.bic", crafted);
    expect_refused("cache info " + d.file("big.bic"), {"big.bic", "header/frame", "1e+39 is not a whole frame number"});
    expect_refused(cornell + " --gi cache --cache-in " + d.file("big.bic"), {"big.bic", "header/frame"});
    // A deep file whose bounce:spp is 2e9 (0 and -5 were refused; the range is 1 .. 4096).
    ASSERT_EQ(test::run_bounce(cornell + " --deep-out " + d.file("f.deep.exr")), 0);
    {
        auto in = OIIO::ImageInput::open(d.file("f.deep.exr"));
        ASSERT_TRUE(in);
        OIIO::ImageSpec spec = in->spec();
        OIIO::DeepData deep;
        ASSERT_TRUE(in->read_native_deep_image(0, 0, deep));
        in->close();
        spec.attribute("bounce:spp", 2000000000);
        auto out = OIIO::ImageOutput::create(d.file("spp.deep.exr"));
        ASSERT_TRUE(out && out->open(d.file("spp.deep.exr"), spec) && out->write_deep_image(deep));
        out->close();
    }
    expect_refused(cornell + " --deep-in " + d.file("spp.deep.exr"),
                   {"spp.deep.exr", "bounce:spp", "2000000000 samples per pixel is outside 1 .. 4096"});
}

TEST(HostileValues, SingularMatricesAndEmptyFileNamesAreRefused) {
    test::TempDir d;
    const auto scene_with = [&](const json& object, const json& materials = json::object()) {
        json j = test::base_scene();
        j["objects"].push_back(object);
        if (!materials.empty()) j["materials"] = materials;
        d.write("s.json", j.dump());
        return "render " + d.file("s.json") + " -q --res 16x16 -o " + d.file("o.exr");
    };
    json zeros = json::array(), rank2 = {1, 0, 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 0, 0, 0, 1};
    for (int i = 0; i < 16; ++i) zeros.push_back(0);
    for (const json& m : {zeros, rank2})
        expect_refused(scene_with({{"type", "sphere"}, {"radius", 1}, {"transform", {{"matrix", m}}}}),
                       {"s.json", "/objects/1/transform/matrix", "singular"});
    json scaled = {2, 0, 0, 0, 0, 2, 0, 0, 0, 0, 2, 1, 0, 0, 0, 1};
    EXPECT_EQ(test::run_bounce(scene_with({{"type", "sphere"}, {"radius", 1}, {"transform", {{"matrix", scaled}}}})), 0);
    expect_refused(scene_with({{"type", "sphere"}, {"radius", 1}, {"material", "m"}}, {{"m", {{"color_texture", ""}}}}),
                   {"s.json", "/materials/m/color_texture", "an empty file name"});
}

TEST(HostileValues, AFileValueAFlagReplacesIsStillChecked) {
    // The same file fails in the lighting tool or on a farm that sets no flag.
    test::TempDir d;
    const auto with = [&](const json& render, const json& camera_extra, const std::string& flags) {
        json j = test::base_scene();
        j["render"] = render;
        for (const auto& [k, v] : camera_extra.items()) j["camera"][k] = v;
        if (camera_extra.contains("resolution") && camera_extra["resolution"].is_object())
            j["animation"] = {{"fps", 24}, {"frames", {1, 2}}};
        d.write("s.json", j.dump());
        return "render " + d.file("s.json") + " -q -o " + d.file("o.exr") + " " + flags;
    };
    expect_refused(with({{"spp", json::array()}}, json::object(), "--spp 1 --res 16x16"), {"s.json", "/render/spp"});
    expect_refused(with({{"threads", 18446744073709551615.0}}, json::object(), "--threads 1 --res 16x16"), {"s.json", "/render/threads"});
    expect_refused(with(json::object(), {{"resolution", {0, 0}}}, "--res 16x16"), {"s.json", "/camera/resolution"});
    // A keyed resolution is refused as it is without the flag: it cannot be animated
    // (issue 65, item 20: with valid keys it was accepted).
    expect_refused(with(json::object(), {{"resolution", {{"keys", {{1, {16, 16}}, {2, {0, 16}}}}}}}, "--res 16x16"),
                   {"s.json", "/camera/resolution", "cannot be animated"});
    expect_refused(with(json::object(), {{"resolution", {{"keys", {{1, {32, 32}}, {2, {16, 16}}}}}}}, "--res 32x32"),
                   {"s.json", "/camera/resolution", "cannot be animated"});
    EXPECT_EQ(test::run_bounce(with({{"spp", 2}}, json::object(), "--spp 1 --res 16x16")), 0);
}

TEST(HostileValues, MessagesSayWhatTheUserWroteAndWhen) {
    test::TempDir d;
    // bake-ao --distance 1e39 was echoed as "--distance inf".
    const std::string displaced = test::source_dir() + "/scenes/displaced/displaced.json";
    expect_refused("bake-ao " + displaced + " --object rounded_cube --distance 1e39 -o " + d.file("ao.exr"),
                   {"--distance 1e+39", "(0, 1e+18]"});
    // A keyed fov that leaves its range at frame 3 says so.
    json j = test::base_scene();
    j["animation"] = {{"fps", 24}, {"frames", {1, 4}}};
    j["camera"]["fov"] = {{"keys", {{1, 40}, {4, 250}}}};
    d.write("k.json", j.dump());
    expect_refused("render " + d.file("k.json") + " -q --res 16x16 --frame 3 -o " + d.file("o.exr"),
                   {"k.json", "/camera/fov", "at frame 3"});
}

TEST(HostileValues, AHundredThousandSpheresAreRefusedBeforeAnyIsTessellated) {
    // They ran for minutes into 14 GB before "the camera sees no geometry".
    test::TempDir d;
    json j = test::base_scene();
    for (int i = 0; i < 100000; ++i)
        j["objects"].push_back({{"type", "sphere"}, {"center", {i % 100 * 3, 1000 + i / 100 * 3, 0}}, {"radius", 1}});
    d.write("s.json", j.dump());
    expect_refused("render " + d.file("s.json") + " -q --res 16x16 -o " + d.file("o.exr"),
                   {"s.json", "/objects", "100000 spheres would be tessellated into 2.18e+09 triangles", "render.memory_budget"});
    // As 20-triangle spheres they fit, and render.
    for (size_t i = 1; i < j["objects"].size(); ++i) j["objects"][i]["subdivisions"] = 0, j["objects"][i]["fine_subdivisions"] = 0;
    d.write("s.json", j.dump());
    EXPECT_EQ(test::run_bounce("render " + d.file("s.json") + " -q --res 16x16 -o " + d.file("o.exr")), 0);
}

TEST(BadInput, CoordinatesThatOverflowFloatAreRefusedAtLoad) {
    test::TempDir d;
    const std::string out = d.file("x.exr");
    refused(render_cmd(test::cornell_scene(), out) + " --set camera.position.0=1e39", {"/camera/position/0", "does not fit a float"});
    nlohmann::json j = test::base_scene();
    j["objects"] = {{{"type", "quad"}, {"vertices", {{0, 0, 0}, {3e38, 0, 0}, {1, 0, 1}, {0, 0, 1}}}}};
    d.write("quad.json", j.dump());
    refused(render_cmd(d.file("quad.json"), out), {"quad.json", "/objects/0/vertices/1/0", "out of range"});
    j = test::base_scene();
    j["lights"] = {{{"type", "point"}, {"position", {1e39, 0, 0}}}};
    d.write("light.json", j.dump());
    refused(render_cmd(d.file("light.json"), out), {"light.json", "/lights/0/position/0"});
    j = test::base_scene();
    j["lights"] = {{{"type", "point"}, {"position", {0, 5, 0}}, {"color", 1e20}, {"intensity", 1e20}}};
    d.write("bright.json", j.dump());
    refused(render_cmd(d.file("bright.json"), out), {"bright.json", "/lights/0/intensity", "exceeds"});
    for (const double power : {-1.0, 1e39, 2000.0}) {  // a spot's cosine_power: 0 .. 1000
        j = test::base_scene();
        j["lights"] = {{{"type", "spot"}, {"position", {0, 5, 0}}, {"cosine_power", power}}};
        d.write("spot.json", j.dump());
        refused(render_cmd(d.file("spot.json"), out), {"spot.json", "/lights/0/cosine_power"});
    }
}

// Found by render_fuzz's 30-minute run (issue 65): an object whose type is a number aborted the
// loader (the sphere memory estimate read the type as a string before read_object checked it).
TEST(BadInput, AnObjectTypeThatIsNotAStringIsNamed) {
    for (const nlohmann::json& type : {nlohmann::json(5), nlohmann::json::array(), nlohmann::json(nullptr)}) {
        nlohmann::json j = test::base_scene();
        j["objects"] = {{{"type", type}}};
        test::expect_input_error([&] { test::scene_from(j); }, {"/objects/0/type"});
    }
}

TEST(BadInput, SubdivisionSurfacesThatCannotBeDiced) {
    test::TempDir d;
    std::string obj;  // a 45 x 45 grid of quads facing the camera
    for (int j = 0; j <= 45; ++j)
        for (int i = 0; i <= 45; ++i) obj += fmt::format("v {} 0 {}\nvt {} {}\n", i - 22.5, j - 22.5, i / 45.0, j / 45.0);
    for (int j = 0; j < 45; ++j)
        for (int i = 0; i < 45; ++i) {
            const int a = j * 46 + i + 1;
            obj += fmt::format("f {0}/{0} {1}/{1} {2}/{2} {3}/{3}\n", a, a + 1, a + 47, a + 46);
        }
    d.write("grid.obj", obj);
    nlohmann::json j = test::base_scene();
    j["objects"] = {{{"file", "grid.obj"}, {"subdivision", "catmull-clark"}, {"displacement", {{"map", "nowhere.png"}, {"scale", 0.1}}}}};
    d.write("nomap.json", j.dump());
    refused(render_cmd(d.file("nomap.json"), d.file("x.exr")), {"nomap.json", "/objects/0/displacement/map", "nowhere.png"});
    j["objects"][0]["displacement"] = {{"map", "grid.obj"}, {"scale", 1e39}};
    d.write("huge.json", j.dump());
    refused(render_cmd(d.file("huge.json"), d.file("x.exr")), {"huge.json", "/objects/0/displacement/scale"});
    j["objects"][0].erase("displacement");
    j["camera"]["resolution"] = {2048, 2048};
    d.write("dense.json", j.dump());
    refused("render " + d.file("dense.json") + " -o " + d.file("x.exr") + " -q --max-level 8 --shading-rate 0.05",
            {"dense.json", "/objects/0", "micropolygons", "render.shading_rate"});
}

TEST(BadInput, FurThatCannotGrow) {
    test::TempDir d;
    nlohmann::json j = test::base_scene();
    auto with_fur = [&](const std::string& name, const nlohmann::json& fur) {
        j["objects"][0]["fur"] = fur;
        return d.write(name, j.dump());
    };
    refused(render_cmd(with_fur("neg.json", {{"count", 10}, {"length", -1}}), d.file("x.exr")), {"neg.json", "/objects/0/fur/length"});
    refused(render_cmd(with_fur("nan.json", {{"count", 10}, {"width_root", "NaN"}}), d.file("x.exr")),
            {"nan.json", "/objects/0/fur/width_root"});
    // 400 strands per unit area on the 2000 x 2000 floor would need ~600 GiB.
    refused(render_cmd(with_fur("dense.json", {{"density", 400}}), d.file("x.exr")),
            {"dense.json", "/objects/0/fur/density", "render.memory_budget"});
    refused(render_cmd(with_fur("map.json", {{"count", 10}, {"density_texture", "gone.png"}}), d.file("x.exr")),
            {"map.json", "/objects/0/fur/density_texture", "gone.png"});
}

TEST(BadInput, SceneFilesThatLie) {
    test::TempDir d;
    d.write("dup.json", R"({"camera": {"position": [0, 1, 5], "look_at": [0, 0, 0]}, "objects": [], "objects": []})");
    refused(render_cmd(d.file("dup.json"), d.file("x.exr")), {"dup.json", "/objects", "given twice"});
    d.write("top.json", "[1, 2]");
    refused(render_cmd(d.file("top.json"), d.file("x.exr")) + " --set camera.fov=40", {"top.json", "expected an object at the top"});
    d.write("short.ply",
            "ply\nformat ascii 1.0\nelement vertex 100\nproperty float x\nproperty float y\nproperty float z\n"
            "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
    nlohmann::json j = test::base_scene();
    j["objects"] = {{{"file", "short.ply"}}};
    d.write("ply.json", j.dump());
    refused(render_cmd(d.file("ply.json"), d.file("x.exr")),
            {"/objects/0/file", "line 13", "vertex 3: 4 values where its properties take 3"});
}

}  // namespace
}  // namespace bounce
