// Hostile inputs that used to crash, hang, pass silently or destroy files: each now exits 2
// with the file and the place, and leaves every file as it was.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <fstream>

#include "bounce/cache/cache_file.h"
#include "bounce/core/error.h"
#include "bounce/core/image.h"
#include "test_util.h"

namespace bounce {
namespace {

void refused(const std::string& args, std::initializer_list<std::string> parts) { test::expect_refused(args, parts); }

std::string render_cmd(const std::string& scene, const std::string& out) { return "render " + scene + " -o " + out + " -q --res 16x16"; }

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

TEST(BadInput, CacheRecordsBeyondFloatRangeAreRefusedAtRead) {
    test::TempDir d;
    ASSERT_EQ(test::run_bounce(render_cmd(test::cornell_scene(), d.file("a.exr")) + " --gi cache --rays 16 --cache-out " + d.file("c.bic")),
              0);
    for (int which = 0; which < 2; ++which) {
        CacheFile f = read_cache_file(d.file("c.bic"));
        if (which == 0)
            f.records[0].p.x = 3e38f;
        else
            f.records[0].E.y = 3e38f;
        // serialize_cache_file writes valid checksums: only the values are wrong.
        std::string bytes = serialize_cache_file(f);
        d.write("bad.bic", bytes);
        refused("cache info " + d.file("bad.bic"), {"bad.bic", "record 0", which == 0 ? "position" : "irradiance"});
        refused(render_cmd(test::cornell_scene(), d.file("b.exr")) + " --gi cache --rays 16 --cache-in " + d.file("bad.bic"),
                {"bad.bic", "record 0"});
    }
}

TEST(BadInput, FifosAndDirectoriesAreNamedNotOpened) {
    test::TempDir d;
    ASSERT_EQ(mkfifo(d.file("scene.json").c_str(), 0600), 0);
    refused(render_cmd(d.file("scene.json"), d.file("x.exr")), {"scene.json", "not a regular file"});
    std::filesystem::create_directory(d.file("adir.json"));
    refused(render_cmd(d.file("adir.json"), d.file("x.exr")), {"adir.json", "is a directory"});
    refused(render_cmd(test::cornell_scene(), d.file("y.exr")) + " --deep-in " + d.file("scene.json"),
            {"scene.json", "not a regular file"});
}

TEST(BadInput, NegativeAndNanFlagsExitTwo) {
    test::TempDir d;
    const std::string cmd = render_cmd(test::cornell_scene(), d.file("x.exr"));
    refused(cmd + " --rays -1", {"--rays -1", "out of range"});
    refused(cmd + " --threads -1", {"--threads -1", "out of range"});
    refused(cmd + " --spp -1", {"--spp -1", "out of range"});
    refused(cmd + " --seed -1", {"--seed -1", "non-negative"});
    refused(cmd + " --min-spacing -1", {"--min-spacing -1", "out of range"});
    refused(cmd + " --min-spacing nan", {"--min-spacing nan", "expected a number"});
    refused(cmd + " --set objects.-1.name=x", {"\"-1\" is not an array index"});
    refused(cmd + " --cache-out " + d.file("c.bic"), {"--cache-out", "--gi cache"});
    refused(cmd + " --cache-in " + d.file("c.bic"), {"--cache-in", "--gi cache"});
    refused("rendr x", {"unknown command", "did you mean \"render\""});
    // A frame that cannot fit is refused up front with the estimate, not with std::bad_alloc.
    refused("render " + test::cornell_scene() + " -o " + d.file("big.exr") + " -q --res 60000x60000",
            {"camera.resolution", "needs about", "GiB"});
}

TEST(BadInput, TheLightingToolRefusesBeforeServing) {
    test::TempDir d;
    const std::string scene = test::cornell_scene(), out = " --out " + d.file("out");
    refused("light " + d.file("nope.json") + out, {"nope.json", "not found"});
    refused("light " + scene + out + " --bind 0.0.0.0", {"--bind", "loopback"});
    refused("light " + scene + out + " --port 70000", {"--port"});
    refused("light " + scene + " --out /dev/null", {"/dev/null", "output folder"});
    refused("light " + scene + out + " --set render.rays=-1", {"--set render.rays=-1", "out of range"});
    refused("light " + scene + out + " --set nonsense", {"--set nonsense", "key=value"});
    // A bad cache or deep file is named and never replaces the session's own.
    std::filesystem::create_directories(d.file("out"));
    d.write("out/session.bic", "the session's cache");
    refused("light " + scene + out + " --cache-in " + scene, {scene, "bad magic"});
    refused("light " + scene + out + " --deep-in " + scene, {scene});
    std::ifstream in(d.file("out/session.bic"));
    EXPECT_EQ(std::string(std::istreambuf_iterator<char>(in), {}), "the session's cache");
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

TEST(BadInput, CompareAndCacheToolsRefuseWhatTheyUsedToAccept) {
    test::TempDir d;
    ASSERT_EQ(
        test::run_bounce(render_cmd(test::cornell_scene(), d.file("a.exr")) + " --gi cache --rays 16 --cache-out " + d.file("gi.bic")), 0);
    ASSERT_EQ(
        test::run_bounce(render_cmd(test::cornell_scene(), d.file("b.exr")) + " --gi cache --ao --rays 16 --cache-out " + d.file("ao.bic")),
        0);
    Image nan = read_exr(d.file("a.exr")), black = nan;
    for (auto& l : nan.layers) std::fill(l.data.begin(), l.data.end(), std::nanf(""));
    for (auto& l : black.layers) std::fill(l.data.begin(), l.data.end(), 0.0f);
    write_exr(d.file("nan.exr"), nan);
    write_exr(d.file("black.exr"), black);
    refused("compare " + d.file("nan.exr") + " " + d.file("a.exr"), {"nan.exr", "not a finite value"});
    std::string out;
    std::string cmd = std::string(BOUNCE_BINARY) + " compare " + d.file("a.exr") + " " + d.file("black.exr") +
                      " --layer indirect --json > " + d.file("c.json");
    ASSERT_EQ(std::system(cmd.c_str()), 0);
    std::ifstream in(d.file("c.json"));
    EXPECT_TRUE(nlohmann::json::parse(in)["indirect"]["rel_rmse"].is_null());  // not "0 %"
    refused("compare " + d.file("a.exr") + " " + d.file("b.exr") + " --diff " + d.file("a.exr"), {"--diff", "is a PNG file (.png)"});
    refused("compare " + d.file("a.exr") + " " + d.file("b.png") + " --diff " + d.file("b.png"), {"b.png", "names an input"});
    // The default difference image (a.diff.png beside the test) must not overwrite a reference of that name.
    std::filesystem::copy_file(d.file("b.exr"), d.file("a.diff.png"), std::filesystem::copy_options::overwrite_existing);
    const std::string reference = test::bytes_of(d.file("a.diff.png"));
    refused("compare " + d.file("a.exr") + " " + d.file("a.diff.png"), {"a.diff.png", "names an input"});
    EXPECT_EQ(test::bytes_of(d.file("a.diff.png")), reference);
    refused("cache merge " + d.file("gi.bic") + " " + d.file("ao.bic") + " -o " + d.file("m.bic"), {"ao.bic", "holds AO"});
    refused("cache filter " + d.file("gi.bic") + " -o " + d.file("f.bic") + " --sphere nan,0,0,1", {"--sphere", "not a finite"});
    refused("cache filter " + d.file("gi.bic") + " -o " + d.file("f.bic") + " --sphere 0,0,0,-1", {"--sphere", "radius must be > 0"});
    refused("cache filter " + d.file("gi.bic") + " -o " + d.file("gi.bic") + " --sphere 0,0,0,1", {"gi.bic", "names an input"});
}

TEST(BadInput, OutputsThatWouldDestroySomethingAreRefusedBeforeRendering) {
    test::TempDir d;
    d.write("scene.json", test::base_scene().dump());
    const std::string scene = d.file("scene.json");
    const std::string before = test::base_scene().dump();
    refused(render_cmd(scene, scene), {"-o", ".exr"});
    refused(render_cmd(scene, d.file("x.png")), {"-o", ".exr"});
    refused(render_cmd(scene, "/dev/null.exr") + " --deep-out /dev/null", {"/dev/null", "not a regular file"});
    std::filesystem::create_directory(d.file("adir.exr"));
    refused(render_cmd(scene, d.file("adir.exr")), {"adir.exr", "is a directory"});
    std::filesystem::create_directory(d.file("sdir"));
    refused(render_cmd(scene, d.file("y.exr")) + " --stats-json " + d.file("sdir"), {"sdir", "is a directory"});
    EXPECT_FALSE(std::filesystem::exists(d.file("y.exr")));  // checked before rendering
    refused(render_cmd(scene, d.file("z.exr")) + " --deep-out " + d.file("z.exr"), {"--deep-out", "same file"});
    std::ifstream in(scene);
    EXPECT_EQ(std::string(std::istreambuf_iterator<char>(in), {}), before);
}

TEST(BadInput, StaleTemporariesOfDeadRendersAreRemoved) {
    test::TempDir d;
    d.write("scene.json", test::base_scene().dump());
    // PID 2^22 + 1 is above Linux's pid_max limit: no such process.
    d.write("x.tmp4194305.exr", "half-written");
    ASSERT_EQ(test::run_bounce(render_cmd(d.file("scene.json"), d.file("x.exr"))), 0);
    EXPECT_FALSE(std::filesystem::exists(d.file("x.tmp4194305.exr")));
    EXPECT_TRUE(std::filesystem::exists(d.file("x.exr")));
}

}  // namespace
}  // namespace bounce
