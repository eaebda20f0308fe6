// Issue 29, files a hostile user can hand bounce: crafted deep files, deeply nested JSON and
// glTF, lying PLY headers, broken textures, keys that would be ignored. Each used to crash,
// hang or render something wrong with exit 0; each now exits 2 naming the file and the place
// (or renders a finite image).
#include <OpenImageIO/imageio.h>
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "bounce/core/error.h"
#include "bounce/core/image.h"
#include "bounce/render/render.h"
#include "test_util.h"

namespace bounce {
namespace {

using nlohmann::json;

std::string render_cmd(const std::string& scene, const std::string& out) { return "render " + scene + " -o " + out + " -q --res 16x16"; }

using test::write_constant_image;

TEST(HostileDeep, EveryFieldOfACraftedDeepFileIsCheckedBeforeShading) {
    test::TempDir d;
    const Scene s =
        load_scene(test::cornell_scene(), {"camera.resolution=[12,12]", "render.spp=1", "render.gi=\"cache\"", "render.rays=16"});
    RenderRequest req;
    req.deep_out = d.file("f.deep.exr");
    Stats stats;
    render(s, req, stats, nullptr);
    const DeepBuffer good = read_deep(req.deep_out);
    // The issue's crafted files: Pref 3e38 or 1e19 everywhere (segfault), Nref NaN, N 1e30, P 3e38
    // on one fragment (abort in Embree), N = 0 everywhere (NaN pixels).
    struct Case {
        const char* name;
        std::function<void(Fragment&)> edit;
        bool all;
        const char* channel;
    };
    const std::vector<Case> cases = {
        {"pref3e38", [](Fragment& f) { f.p_base.x = 3e38f; }, true, "Pref"},
        {"pref1e19", [](Fragment& f) { f.p_base.x = 1e19f; }, true, "Pref"},
        {"nrefnan", [](Fragment& f) { f.n_base.x = NAN; }, false, "Nref"},
        {"n1e30", [](Fragment& f) { f.n.x = 1e30f; }, false, "N"},
        {"p3e38", [](Fragment& f) { f.p.x = 3e38f; }, false, "P"},
        {"nzero", [](Fragment& f) { f.n = Vec3(0); }, true, "N"},
        {"footprint", [](Fragment& f) { f.footprint = -1; }, false, "footprint"},
        {"far", [](Fragment& f) { f.p.x = 1e17f; }, false, "outside the scene"},
    };
    for (const Case& c : cases) {
        DeepBuffer bad = good;
        for (Fragment& f : bad.fragments) {
            c.edit(f);
            if (!c.all) break;
        }
        const std::string file = d.file(std::string(c.name) + ".deep.exr");
        write_deep(file, bad);
        RenderRequest in;
        in.deep_in = file;
        try {
            render(s, in, stats, nullptr);
            ADD_FAILURE() << c.name << " was shaded";
        } catch (const InputError& e) {
            EXPECT_EQ(e.file(), file);
            EXPECT_NE(std::string(e.what()).find(c.channel), std::string::npos) << e.what();
        }
    }
}

TEST(HostileExr, AHeaderOpenImageIoAbortsOnIsRefusedWhereverAnExrIsRead) {
    // A deep file the fuzzer damaged: OpenImageIO 2.4 aborts the process on its channel list
    // ("Unknown Imf::PixelType 3"); OpenEXR's core library names the bad pixel type.
    const std::string bad = test::source_dir() + "/tests/data/hostile/oiio-abort-pixel-type.exr";
    test::TempDir d;
    const Scene s = load_scene(test::cornell_scene(), {"camera.resolution=[8,8]", "render.spp=1"});
    RenderRequest in;
    in.deep_in = bad;
    Stats stats;
    try {
        render(s, in, stats, nullptr);
        ADD_FAILURE() << "a damaged deep file was read";
    } catch (const InputError& e) {
        EXPECT_EQ(e.file(), bad);
        EXPECT_NE(std::string(e.what()).find("damaged OpenEXR header: Invalid pixel type"), std::string::npos) << e.what();
    }
    std::filesystem::copy_file(bad, d.file("t.exr"));
    json j = test::base_scene();
    j["materials"] = {{"m", {{"color_texture", "t.exr"}}}};
    j["objects"][0]["material"] = "m";
    d.write("m.json", j.dump());
    test::expect_refused(render_cmd(d.file("m.json"), d.file("o.exr")), {"m.json", "/materials/m/color_texture", "damaged OpenEXR header"});
    j = test::base_scene();
    j["lights"] = {{{"type", "sky"}, {"texture", "t.exr"}}};
    d.write("sky.json", j.dump());
    test::expect_refused(render_cmd(d.file("sky.json"), d.file("o.exr")), {"sky.json", "/lights/0/texture", "damaged OpenEXR header"});
}

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

/// A glTF (JSON only, embedded buffer) of one triangle under a chain of `depth` nodes.
json gltf_chain(int depth) {
    json g = {{"asset", {{"version", "2.0"}}}, {"scene", 0}, {"scenes", {{{"nodes", {0}}}}}};
    const std::string tri = "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA";  // (0,0,0) (1,0,0) (0,1,0)
    g["buffers"] = {{{"byteLength", 36}, {"uri", "data:application/octet-stream;base64," + tri}}};
    g["bufferViews"] = {{{"buffer", 0}, {"byteLength", 36}}};
    g["accessors"] = {{{"bufferView", 0}, {"componentType", 5126}, {"count", 3}, {"type", "VEC3"}, {"min", {0, 0, 0}}, {"max", {1, 1, 0}}}};
    g["meshes"] = {{{"primitives", {{{"attributes", {{"POSITION", 0}}}}}}}};
    json nodes = json::array();
    for (int i = 0; i < depth; ++i) nodes.push_back(i + 1 < depth ? json{{"children", {i + 1}}} : json{{"mesh", 0}});
    g["nodes"] = nodes;
    return g;
}

TEST(HostileGltf, DeepNodeChainsCyclesAndTruncatedFilesAreRefusedBeforeAssimp) {
    test::TempDir d;
    auto scene_with = [&](const std::string& mesh) {
        json j = test::base_scene();
        j["objects"] = {{{"type", "mesh"}, {"file", mesh}}};
        return d.write("s.json", j.dump());
    };
    d.write("ok.gltf", gltf_chain(3).dump());
    EXPECT_NO_THROW(load_scene(scene_with("ok.gltf")));
    d.write("deep.gltf", gltf_chain(20000).dump());  // 20 000 levels segfaulted inside Assimp
    test::expect_refused(render_cmd(scene_with("deep.gltf"), d.file("o.exr")), {"deep.gltf", "/nodes/", "deeper than 1000"});
    json cyc = gltf_chain(3);
    cyc["nodes"][2]["children"] = {0};
    d.write("cycle.gltf", cyc.dump());
    test::expect_refused(render_cmd(scene_with("cycle.gltf"), d.file("o.exr")), {"cycle.gltf", "/nodes", "cycle"});
    const std::string text = gltf_chain(3).dump();
    d.write("cut.gltf", text.substr(0, text.size() / 2));  // "No suitable reader" before
    test::expect_refused(render_cmd(scene_with("cut.gltf"), d.file("o.exr")), {"cut.gltf", "malformed glTF JSON"});
    json missing = gltf_chain(3);
    missing["images"] = {{{"uri", "nosuch.png"}}};
    d.write("img.gltf", missing.dump());
    test::expect_refused(render_cmd(scene_with("img.gltf"), d.file("o.exr")), {"img.gltf", "/images/0/uri", "nosuch.png"});
    // data: URIs: base64 of a whole number of quads (mesh_file_fuzz: one of 1, 2 or 3 characters
    // made Assimp 5.2 read past its decoded buffer), of its own alphabet, as long as byteLength says.
    const auto refused_uri = [&](const std::string& uri, size_t length, const std::vector<std::string>& parts) {
        json g = gltf_chain(3);
        g["buffers"] = {{{"byteLength", length}, {"uri", uri}}};
        d.write("uri.gltf", g.dump());
        std::vector<std::string> want{"uri.gltf", "/buffers/0/uri"};
        want.insert(want.end(), parts.begin(), parts.end());
        test::expect_refused(render_cmd(scene_with("uri.gltf"), d.file("o.exr")), want);
    };
    refused_uri("data:application/octet-stream;base64,A", 0, {"1 characters, not a multiple of 4"});
    refused_uri("data:application/octet-stream;base64,AA&A", 0, {"outside its alphabet"});
    refused_uri("data:application/octet-stream;base64,AAAA", 8, {"3 bytes", "byteLength 8"});
    refused_uri("data:application/octet-stream,AAAA", 3, {"data:<media type>;base64,<data>"});
}

TEST(HostileGltf, MaterialFactorsAreCheckedAsJsonMaterialsAre) {
    test::TempDir d;
    json j = test::base_scene();
    j["objects"] = {{{"type", "mesh"}, {"file", "m.gltf"}}};
    d.write("s.json", j.dump());
    json emissive = json::object(), base = json::object();
    emissive["emissiveFactor"] = json::array({1e39, 1, 1});
    base["pbrMetallicRoughness"]["baseColorFactor"] = json::array({5, 5, 5, 1});
    for (const auto& [material, says] : {std::pair{emissive, "emission"}, std::pair{base, "base colour"}}) {
        json g = gltf_chain(1);
        g["materials"] = json::array({material});
        g["meshes"][0]["primitives"][0]["material"] = 0;
        d.write("m.gltf", g.dump());
        test::expect_refused(render_cmd(d.file("s.json"), d.file("o.exr")), {"m.gltf", "material", says});
    }
}

TEST(HostilePly, BinaryHeadersThatDeclareMoreThanTheFileHoldsAreCorrupted) {
    test::TempDir d;
    for (const char* count : {"100000000", "4000000000"}) {
        std::ofstream(d.file("big.ply"), std::ios::binary)
            << "ply\nformat binary_little_endian 1.0\nelement vertex " << count
            << "\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\n"
               "end_header\n"
            << std::string(64, '\0');
        json j = test::base_scene();
        j["objects"] = {{{"type", "mesh"}, {"file", "big.ply"}}};
        d.write("s.json", j.dump());
        test::expect_refused(render_cmd(d.file("s.json"), d.file("o.exr")), {"big.ply", "header", "corrupted", count});
    }
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

TEST(HostileTextures, NanAndInfiniteTexelsInEveryMaterialSlotGiveAFiniteImage) {
    test::TempDir d;
    for (float bad : {NAN, INFINITY, 1e30f}) {
        write_constant_image(d.file("bad.exr"), 8, 8, 3, bad);
        write_constant_image(d.file("bad1.exr"), 8, 8, 1, bad);
        json j = test::base_scene();
        j["materials"] = {{"m", {{"color_texture", "bad.exr"}, {"bump_texture", "bad1.exr"}, {"ao_texture", "bad1.exr"}}},
                          {"n", {{"color_texture", "bad.exr"}, {"normal_texture", "bad.exr"}}}};
        j["objects"] = {{{"type", "quad"}, {"material", "m"}, {"vertices", {{-5, 0, -5}, {-5, 0, 5}, {0, 0, 5}, {0, 0, -5}}}},
                        {{"type", "quad"}, {"material", "n"}, {"vertices", {{0, 0, -5}, {0, 0, 5}, {5, 0, 5}, {5, 0, -5}}}}};
        j["lights"] = {{{"type", "distant"}, {"direction", {0.3, -1, 0.2}}}};
        d.write("t.json", j.dump());
        for (const char* gi : {"none", "brute", "cache"}) {
            Stats stats;
            const RenderResult r =
                render(load_scene(d.file("t.json"), {Override(fmt::format("render.gi=\"{}\"", gi)), "render.rays=16"}), {}, stats, nullptr);
            for (float v : r.image.find("beauty")->data) ASSERT_TRUE(std::isfinite(v)) << gi << " texel " << bad;
        }
    }
    // A sky texture is read whole and checked: a bad texel is named.
    write_constant_image(d.file("sky.exr"), 8, 4, 3, NAN);
    json j = test::base_scene();
    j["lights"] = {{{"type", "sky"}, {"texture", "sky.exr"}}};
    d.write("sky.json", j.dump());
    test::expect_refused(render_cmd(d.file("sky.json"), d.file("o.exr")), {"sky.json", "/lights/0/texture", "pixel (0, 0)"});
}

TEST(HostileTextures, FurMapsWithNanAndFurColoursAboveOneAreRefused) {
    test::TempDir d;
    write_constant_image(d.file("density.exr"), 4, 4, 1, NAN);
    json j = test::base_scene();
    j["objects"][0]["fur"] = {{"count", 100}, {"length", 0.1}, {"density_texture", "density.exr"}};
    d.write("f.json", j.dump());
    test::expect_refused(render_cmd(d.file("f.json"), d.file("o.exr")), {"f.json", "/objects/0/fur/density_texture", "not a finite"});
    j["objects"][0]["fur"] = {{"count", 100}, {"length", 0.1}, {"color_root", 2}};
    d.write("c.json", j.dump());
    test::expect_refused(render_cmd(d.file("c.json"), d.file("o.exr")), {"c.json", "/objects/0/fur/color_root", "<= 1"});
}

TEST(HostileTextures, HugeUntiledTexturesAreRefusedWithTheWayOut) {
    test::TempDir d;
    write_constant_image(d.file("huge.png"), 8200, 8200, 1, 0.5f);  // 20 000^2 took 256 s for a 32x32 render
    json j = test::base_scene();
    j["materials"] = {{"m", {{"color_texture", "huge.png"}}}};
    j["objects"][0]["material"] = "m";
    d.write("h.json", j.dump());
    test::expect_refused(render_cmd(d.file("h.json"), d.file("o.exr")), {"h.json", "/materials/m/color_texture", "maketx"});
}

TEST(HostileMeshes, AVertexWithThousandsOfFacesOrANanOnACageIsRefusedUpFront) {
    test::TempDir d;
    {
        std::ofstream f(d.file("fan.obj"));
        const int n = 2000;  // 275 s in OpenSubdiv before
        f << "v 0 0 0\n";
        for (int i = 0; i < n; ++i) f << fmt::format("v {} 0 {}\n", std::cos(2 * M_PI * i / n), std::sin(2 * M_PI * i / n));
        for (int i = 0; i < n; ++i) f << fmt::format("f 1 {} {}\n", 2 + (i + 1) % n, 2 + i);
    }
    json j = test::base_scene();
    j["objects"] = {{{"type", "mesh"}, {"file", "fan.obj"}, {"subdivision", "catmull-clark"}}};
    d.write("fan.json", j.dump());
    test::expect_refused(render_cmd(d.file("fan.json"), d.file("o.exr")), {"fan.obj", "vertex 0", "more than 256 faces"});
    d.write("nan.obj", "v 0 0 0\nv 1 0 0\nv nan 0 1\nv 0 0 1\nf 1 2 3 4\n");
    j["objects"][0]["file"] = "nan.obj";
    d.write("nan.json", j.dump());
    test::expect_refused(render_cmd(d.file("nan.json"), d.file("o.exr")), {"nan.obj", "vertex", "not finite"});
    // A displacement map holding NaN is named, at the texel, not blamed on a transform.
    d.write("grid.obj", "v 0 0 0\nv 1 0 0\nv 1 0 1\nv 0 0 1\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nf 1/1 2/2 3/3 4/4\n");
    write_constant_image(d.file("nan.exr"), 4, 4, 1, NAN);
    j["objects"] = {
        {{"type", "mesh"}, {"file", "grid.obj"}, {"subdivision", "catmull-clark"}, {"displacement", {{"map", "nan.exr"}, {"scale", 0.1}}}}};
    d.write("disp.json", j.dump());
    test::expect_refused(render_cmd(d.file("disp.json"), d.file("o.exr")), {"disp.json", "displacement/map", "nan.exr", "near uv"});
}

TEST(HostileMeshes, AMillionMtlMaterialsAreRefusedBeforeAssimp) {
    test::TempDir d;
    {
        std::ofstream m(d.file("many.mtl"));
        for (int i = 0; i < 70000; ++i) m << "newmtl m" << i << "\nKd 0.5 0.5 0.5\n";
    }
    d.write("m.obj", "mtllib many.mtl\nv 0 0 0\nv 1 0 0\nv 0 0 1\nusemtl m0\nf 1 2 3\n");
    json j = test::base_scene();
    j["objects"] = {{{"type", "mesh"}, {"file", "m.obj"}}};
    d.write("m.json", j.dump());
    test::expect_refused(render_cmd(d.file("m.json"), d.file("o.exr")), {"many.mtl", "line 131073", "more than 65536 materials"});
}

}  // namespace
}  // namespace bounce
