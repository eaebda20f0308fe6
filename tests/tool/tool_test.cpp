// The lighting tool: the session's edit / re-shade / re-gather / sub-viewport / cancel contract
// (its HTTP API: tool_http_test.cpp).
#include <fmt/format.h>
#include <httplib.h>

#include <cstring>
#include <fstream>
#include <map>
#include <thread>

#include "bounce/cache/cache_file.h"
#include "bounce/core/error.h"
#include "bounce/gather/gather.h"
#include "bounce/config/params.h"
#include "bounce/tool/server.h"
#include "tool_util.h"

namespace bounce {
namespace {

using nlohmann::json;
using test::bytes_of, test::render_and_wait, test::small_session;

TEST(LightingTool, ParamsListTheTableAndTheScenesMaterials) {
    test::TempDir d;
    LightingSession s(small_session(d));
    const json rows = s.params();
    size_t table = 0;
    json rays, emission;
    for (const json& r : rows) {
        table += find_param(scene_params(), r["key"]) != nullptr;
        if (r["key"] == "render.rays") rays = r;
        if (r["key"] == "materials.light.emission") emission = r;
    }
    EXPECT_EQ(table, scene_params().size());
    EXPECT_EQ(rays["value"], 64);
    EXPECT_EQ(rays["default"], IndirectSettings{}.rays);
    EXPECT_EQ(rays["needs"], "regather");
    EXPECT_EQ(emission["value"], json({17, 12, 4}));
    EXPECT_EQ(emission["needs"], "reshade");
    // The tool starts with the cache when the scene renders no indirect light.
    for (const json& r : rows)
        if (r["key"] == "render.gi") {
            EXPECT_EQ(r["value"], "cache");
        }
}

TEST(LightingTool, EveryFieldALightOrMaterialReadsHasARowEvenAtItsDefault) {
    // The scene leaves the spot's cone and the light material's roughness at their defaults:
    // rows show them with the reader's defaults (Light{}, Material{}), and they can be edited.
    test::TempDir d;
    SessionOptions o = small_session(d);
    o.sets.push_back(R"(lights=[{"type": "spot", "position": [278, 540, 278], "intensity": 5}])");
    LightingSession s(o);
    std::map<std::string, json> rows;
    for (const json& r : s.params()) rows[r["key"]] = r;
    ASSERT_TRUE(rows.count("lights.0.cone_angle"));
    EXPECT_EQ(rows["lights.0.cone_angle"]["value"], Light{}.cone_angle);
    EXPECT_EQ(rows["lights.0.cone_angle"]["default"], Light{}.cone_angle);
    EXPECT_EQ(rows["lights.0.cone_falloff"]["value"], Light{}.cone_falloff);
    EXPECT_EQ(rows["lights.0.cosine_power"]["value"], Light{}.cosine_power);
    EXPECT_EQ(rows["lights.0.direction"]["value"], json({0, -1, 0}));
    EXPECT_EQ(rows["lights.0.intensity"]["value"], 5);
    EXPECT_EQ(rows["lights.0.intensity"]["default"], 1);
    EXPECT_EQ(rows["lights.0.intensity"]["stage"], "light");
    EXPECT_EQ(rows.count("lights.0.corner"), 0u);  // a spot does not read it
    ASSERT_TRUE(rows.count("materials.light.roughness"));
    EXPECT_EQ(rows["materials.light.roughness"]["value"], Material{}.roughness);
    EXPECT_EQ(rows["materials.light.roughness"]["stage"], "material");
    EXPECT_EQ(s.edit("lights.0.cone_angle", 40)["needs"], "reshade");
    for (const json& r : s.params())
        if (r["key"] == "lights.0.cone_angle") {
            EXPECT_EQ(r["value"], 40);
        }
}

TEST(LightingTool, EditsMayNotReadOrWriteFilesOutsideTheSceneAndOutputFolders) {
    // Every path-valued key an edit sets obeys the file API's confinement: a mesh, a texture
    // or the radiosity folder outside both folders is refused, and nothing is created there.
    test::TempDir d, elsewhere;
    LightingSession s(small_session(d));
    const std::string mesh = elsewhere.write("stolen.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    std::filesystem::create_symlink(elsewhere.path(), d.path() / "scene" / "link");
    auto refused = [&](const std::string& key, const json& value, const std::string& outside) {
        try {
            s.edit(key, value);
            ADD_FAILURE() << key << " = " << value << " was taken";
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find("lighting tool: edit " + key), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find(outside + "' is outside the scene's folder and the output folder"), std::string::npos)
                << e.what();
        }
    };
    refused("objects.6.file", mesh, mesh);
    refused("objects.0", json{{"file", mesh}}, mesh);
    refused("objects.6.file", "link/stolen.obj", "link/stolen.obj");
    refused("materials.white.color_texture", elsewhere.path().string() + "/../" + elsewhere.path().filename().string() + "/stolen.obj",
            "stolen.obj");
    const std::string folder = (elsewhere.path() / "made").string();
    refused("render.radiosity_textures", folder, folder);
    EXPECT_FALSE(std::filesystem::exists(folder));
    // Inside them, the same keys are taken.
    std::filesystem::copy_file(mesh, d.path() / "scene" / "mine.obj");
    EXPECT_EQ(s.edit("objects.6.file", "mine.obj")["key"], "objects.6.file");
    EXPECT_EQ(s.edit("render.radiosity_textures", d.file("out/textures"))["key"], "render.radiosity_textures");
    // A relative folder is the scene folder's, as the saved scene will read it (it was taken
    // as the working directory's and refused as outside).
    std::filesystem::create_directories(d.path() / "scene" / "textures");
    EXPECT_EQ(s.edit("render.radiosity_textures", "textures")["key"], "render.radiosity_textures");
    refused("render.radiosity_textures", "../../" + elsewhere.path().filename().string(), elsewhere.path().filename().string());
}

TEST(LightingTool, TheFilesAMeshNamesAreConfinedAsTheMeshItself) {
    // A mesh inside the scene folder whose MTL, texture, or glTF buffer lies outside both
    // folders: refused with that file's name before anything opens it.
    test::TempDir d, elsewhere;
    LightingSession s(small_session(d));
    elsewhere.write("evil.mtl", "newmtl m\nKd 1 0 0\n");
    const std::string outside = elsewhere.path().string();
    const std::string tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    d.write("scene/mtl.obj", "mtllib " + outside + "/evil.mtl\nusemtl m\n" + tri);
    std::filesystem::create_directories(d.path() / "scene" / "sub");
    const std::string up = std::string("../../") + elsewhere.path().filename().string();
    d.write("scene/sub/rel.obj", "mtllib ../" + up + "/evil.mtl\nusemtl m\n" + tri);
    elsewhere.write("tex.png", "not read");
    d.write("scene/tex.mtl", "newmtl t\nKd 1 1 1\nmap_Kd " + outside + "/tex.png\n");
    d.write("scene/tex.obj", "mtllib tex.mtl\nusemtl t\n" + tri);
    elsewhere.write("tri.bin", std::string(36, '\0'));
    json gltf = {{"asset", {{"version", "2.0"}}}, {"buffers", {{{"byteLength", 36}, {"uri", outside + "/tri.bin"}}}}};
    d.write("scene/far.gltf", gltf.dump());
    for (const auto& [file, named] : std::vector<std::pair<std::string, std::string>>{
             {"mtl.obj", "evil.mtl"}, {"sub/rel.obj", "evil.mtl"}, {"tex.obj", "tex.png"}, {"far.gltf", "tri.bin"}}) {
        try {  // the whole object, without a material: the file's own are read
            s.edit("objects.6", json{{"name", "short_block"}, {"type", "mesh"}, {"file", file}});
            ADD_FAILURE() << file << " was taken";
        } catch (const InputError& e) {
            const std::string what = e.what();
            EXPECT_NE(what.find(named + "' is outside the scene's folder and the output folder"), std::string::npos)
                << file << ": " << what;
        }
    }
    // The same mesh with its MTL beside it is taken.
    d.write("scene/ok.mtl", "newmtl m\nKd 1 0 0\n");
    d.write("scene/ok.obj", "mtllib ok.mtl\nusemtl m\n" + tri);
    EXPECT_EQ(s.edit("objects.6", json{{"name", "short_block"}, {"type", "mesh"}, {"file", "ok.obj"}})["key"], "objects.6");
}

TEST(LightingTool, ALightEditReshadesWithoutNewRecordsOrVisibility) {
    test::TempDir d;
    LightingSession s(small_session(d));
    render_and_wait(s, SessionAction::Rasterize);
    const std::string cache = bytes_of(s.cache_path());
    const auto before = s.pixels("beauty", 0);
    EXPECT_EQ(s.edit("materials.light.emission", {34, 24, 8})["needs"], "reshade");
    EXPECT_EQ(s.pending(), SessionAction::Reshade);
    render_and_wait(s, SessionAction::Reshade);
    EXPECT_EQ(s.status()["pending"], nullptr);
    const json st = s.status()["stats"];
    EXPECT_EQ(st["records_new"], 0.0);
    EXPECT_EQ(st["records"], static_cast<double>(read_cache_file(s.cache_path().string()).records.size()));
    EXPECT_EQ(st["rays"]["gather"], 0);
    EXPECT_EQ(st["rays"]["camera"], 0);
    EXPECT_FALSE(st["phases_s"].contains("visibility"));
    EXPECT_NE(s.pixels("beauty", 0).rgba, before.rgba);
    EXPECT_EQ(bytes_of(s.cache_path()), cache);  // the cache is untouched
    // ... so the bounce light is the old light's until a full re-gather.
    EXPECT_EQ(s.status()["bounce_stale"], true);
    render_and_wait(s, SessionAction::Regather, std::array<int, 4>{0, 16, 0, 16});
    EXPECT_EQ(s.status()["bounce_stale"], true);  // a sub-viewport re-gathers only its rectangle
    render_and_wait(s, SessionAction::Regather);
    EXPECT_EQ(s.status()["bounce_stale"], false);
    // Gloss changes how a surface reflects light to the camera, not the light that bounces.
    s.edit("materials.white.specular", {0.2, 0.2, 0.2});
    render_and_wait(s, SessionAction::Reshade);
    EXPECT_EQ(s.status()["bounce_stale"], false);
}

TEST(LightingTool, AnIntensityOrColourEditUpdatesTheBounceLightExactly) {
    test::TempDir d;
    SessionOptions o = small_session(d);
    // A spot through the open front besides the ceiling panel (a mesh light: its emission is a material's).
    o.sets.push_back(R"(lights=[{"type":"spot","position":[278,300,-500],"direction":[0,-0.2,1],"cone_angle":30,"color":2e5}])");
    LightingSession s(o);
    EXPECT_EQ(s.params().dump().find("render.light_parts") != std::string::npos, true);
    render_and_wait(s, SessionAction::Rasterize);
    size_t spot = 0;
    for (const json& row : s.params())
        if (row["key"] == "lights.1.cone_angle") spot = 1;
    const std::string key = fmt::format("lights.{}.", spot);
    EXPECT_EQ(s.edit(key + "intensity", 0.4)["needs"], "reshade");
    EXPECT_EQ(s.edit(key + "color", json{1.0, 0.5, 0.2})["needs"], "reshade");
    render_and_wait(s, SessionAction::Reshade);
    const json st = s.status();
    EXPECT_EQ(st["bounce_stale"], false);  // the records took the new light
    EXPECT_EQ(st["stats"]["records_new"], 0.0);
    EXPECT_EQ(st["stats"]["rays"]["gather"], 0);
    const Image reshaded = s.image();
    render_and_wait(s, SessionAction::Regather);
    const Image regathered = s.image();
    const Layer *a = reshaded.find("indirect"), *b = regathered.find("indirect");
    ASSERT_TRUE(a && b);
    size_t lit = 0;
    for (int y = 0; y < reshaded.height; ++y)
        for (int x = 0; x < reshaded.width; ++x) {
            ASSERT_EQ(reshaded.at(*a, x, y)[0], regathered.at(*b, x, y)[0]) << x << "," << y;
            ASSERT_EQ(reshaded.at(*a, x, y)[2], regathered.at(*b, x, y)[2]) << x << "," << y;
            lit += reshaded.at(*a, x, y)[0] > 0;
        }
    EXPECT_GT(lit, 100u);
    // Moving the light, or the panel's emission, is not a rescale: stale until a re-gather.
    s.edit(key + "position", json{200, 300, -500});
    render_and_wait(s, SessionAction::Reshade);
    EXPECT_EQ(s.status()["bounce_stale"], true);
}

TEST(LightingTool, AReshadeOfACacheWithHolesGathersThem) {
    test::TempDir d;
    LightingSession s(small_session(d));
    render_and_wait(s, SessionAction::Rasterize);
    // Drop the records of the left half of the room (x > 278 mm): those fragments now miss.
    CacheFile f = read_cache_file(s.cache_path().string());
    const size_t before = f.records.size();
    std::erase_if(f.records, [](const Record& r) { return r.p.x > 278; });
    f.fragment_records.clear();
    write_cache_file(d.file("out/holes.bic"), f);
    s.load_cache("holes.bic");
    render_and_wait(s, SessionAction::Reshade);
    const json st = s.status()["stats"];
    EXPECT_GT(st["records_new"].get<double>(), 0.0);
    EXPECT_LT(f.records.size(), before);
    EXPECT_EQ(st["shading_misses"].get<double>(), 0.0);
    EXPECT_EQ(read_cache_file(s.cache_path().string()).records.size(), f.records.size() + st["records_new"].get<size_t>());
}

TEST(LightingTool, RegatherReplacesTheRecords) {
    test::TempDir d;
    LightingSession s(small_session(d));
    render_and_wait(s, SessionAction::Rasterize);
    EXPECT_EQ(s.edit("render.rays", 100)["needs"], "regather");
    render_and_wait(s, SessionAction::Regather);
    const CacheFile f = read_cache_file(s.cache_path().string());
    ASSERT_GT(f.records.size(), 10u);
    size_t old = 0;
    for (const Record& r : f.records) old += r.rays != static_cast<uint32_t>(gather_grid(100).rays());
    EXPECT_EQ(old, 0u);
    EXPECT_EQ(s.status()["stats"]["records_new"].get<double>(), static_cast<double>(f.records.size()));
}

TEST(LightingTool, SubViewportReshadeChangesOnlyItsRectangleAndEqualsAFullReshade) {
    test::TempDir d1, d2;
    LightingSession s(small_session(d1)), full(small_session(d2));
    render_and_wait(s, SessionAction::Rasterize);
    render_and_wait(full, SessionAction::Rasterize);
    const auto before = s.pixels("beauty", 0);
    for (LightingSession* x : {&s, &full}) x->edit("materials.light.emission", {8, 6, 2});
    const std::array<int, 4> crop = {10, 30, 5, 25};
    render_and_wait(s, SessionAction::Reshade, crop);
    render_and_wait(full, SessionAction::Reshade);
    const auto a = s.pixels("beauty", 0), b = full.pixels("beauty", 0);
    ASSERT_EQ(a.width, 48);
    size_t inside_differs = 0, outside_changed = 0, inside_changed = 0;
    for (int y = 0; y < 40; ++y)
        for (int x = 0; x < 48; ++x) {
            const size_t i = 4 * (static_cast<size_t>(y) * 48 + static_cast<size_t>(x));
            const bool in = x >= crop[0] && x < crop[1] && y >= crop[2] && y < crop[3];
            const bool changed = a.rgba.compare(i, 4, before.rgba, i, 4) != 0;
            if (in) {
                inside_differs += a.rgba.compare(i, 4, b.rgba, i, 4) != 0;
                inside_changed += changed;
            } else {
                outside_changed += changed;
            }
        }
    EXPECT_EQ(outside_changed, 0u);
    EXPECT_EQ(inside_differs, 0u);
    EXPECT_GT(inside_changed, 300u);
    EXPECT_THROW(s.start(SessionAction::Reshade, std::array<int, 4>{0, 49, 0, 10}), InputError);
}

TEST(LightingTool, ANewRequestCancelsTheRunningOneAndAFailureKeepsTheImage) {
    test::TempDir d;
    SessionOptions o = small_session(d);
    LightingSession s(o);
    render_and_wait(s, SessionAction::Rasterize);
    const std::string cache = bytes_of(s.cache_path());
    const uint64_t version = s.status()["image"]["version"];
    s.edit("render.rays", 60000);
    s.edit("render.preview", false);
    s.start(SessionAction::Regather);
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    s.stop();
    EXPECT_EQ(s.status()["state"], "cancelled");
    EXPECT_EQ(s.status()["image"]["version"], version);
    EXPECT_EQ(bytes_of(s.cache_path()), cache);
    // A bad value or a bad cache file changes nothing; a render that fails (a camera edit
    // makes the deep buffer another camera's) leaves the image and says why.
    try {  // blamed on the edit, not on the command line or the scene file
        s.edit("render.rays", -1);
        ADD_FAILURE() << "a bad edit was taken";
    } catch (const InputError& e) {
        EXPECT_STREQ(e.what(), "lighting tool: edit render.rays=-1 (/render/rays): error: -1 is out of range [1, 1048576]");
    }
    std::ofstream(d.file("out/bad.bic"), std::ios::binary) << "not a cache";
    EXPECT_THROW(s.load_cache("bad.bic"), InputError);
    EXPECT_EQ(bytes_of(s.cache_path()), cache);
    EXPECT_EQ(s.edit("camera.fov", 30)["needs"], "rasterize");
    s.start(SessionAction::Reshade);
    s.wait();
    EXPECT_EQ(s.status()["state"], "failed");
    EXPECT_NE(s.status()["message"].get<std::string>().find("deep"), std::string::npos) << s.status()["message"];
    EXPECT_EQ(s.status()["image"]["version"], version);
}

TEST(LightingTool, AStoppedRenderLeavesThePreviousImageNotItsPreview) {
    test::TempDir d;
    LightingSession s(small_session(d));
    render_and_wait(s, SessionAction::Rasterize);
    const auto before = s.pixels("beauty", 0);
    s.edit("render.rays", 20000);  // previews on (the session's default): each sub-pass shows
    s.start(SessionAction::Regather);
    for (int i = 0; i < 2000 && s.status()["image"]["version"].get<uint64_t>() == before.version; ++i)
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    ASSERT_GT(s.status()["image"]["version"].get<uint64_t>(), before.version) << "no preview arrived";
    s.stop();
    s.wait();
    ASSERT_EQ(s.status()["state"], "cancelled");
    const auto after = s.pixels("beauty", 0);
    EXPECT_GT(after.version, before.version);  // pages fetch it again
    EXPECT_EQ(after.rgba, before.rgba);
}

TEST(LightingTool, RequestsFromManyThreadsRunOneAtATime) {
    test::TempDir d;
    LightingSession s(small_session(d));
    render_and_wait(s, SessionAction::Rasterize);
    std::vector<std::thread> clients;
    for (int i = 0; i < 4; ++i)
        clients.emplace_back([&s, i] {
            s.start(i % 2 ? SessionAction::Reshade : SessionAction::Regather);
            (void)s.status();
            if (i == 3) s.stop();
        });
    for (auto& t : clients) t.join();
    s.wait();
    render_and_wait(s, SessionAction::Reshade);  // the session is still usable
    EXPECT_EQ(s.status()["stats"]["shading_misses"], 0.0);
}

/// A server on a free loopback port, serving in the background.

}  // namespace
}  // namespace bounce
