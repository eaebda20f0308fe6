// The `bounce` command line: exit statuses, one-line errors, and outputs that are either
// complete or untouched.
#include <gtest/gtest.h>

#include "bounce/core/image.h"
#include "test_util.h"

namespace bounce {
namespace {

using test::run_bounce;

std::string read_file(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), {}};
}

TEST(Cli, RendersTheCornellBoxWithAllLayers) {
    test::TempDir d;
    std::string out = d.file("c.exr");
    ASSERT_EQ(run_bounce("render " + test::cornell_scene() + " -o " + out + " --res 32x32 --spp 2 -q --stats-json " + d.file("stats.json")),
              0);
    Image img = read_exr(out);
    for (const char* layer : {"beauty", "direct", "albedo", "N", "depth"}) EXPECT_NE(img.find(layer), nullptr) << layer;
    EXPECT_EQ(img.metadata["render.spp"], "2");
    EXPECT_TRUE(std::filesystem::exists(d.file("c.png")));
    auto stats = nlohmann::json::parse(read_file(d.file("stats.json")));
    EXPECT_EQ(stats["rays"]["camera"].get<int>(), 32 * 32 * 2);
    EXPECT_GT(stats["rays"]["shadow"].get<int>(), 0);
    EXPECT_TRUE(stats["phases_s"].contains("shading"));
    // No temporary files are left behind.
    for (const auto& e : std::filesystem::directory_iterator(d.path()))
        EXPECT_EQ(e.path().string().find(".tmp"), std::string::npos) << e.path();
}

TEST(Cli, BadInputExitsWithStatusTwoAndOneLine) {
    test::TempDir d;
    std::string err;
    auto check = [&](const std::string& args, const std::string& expect) {
        EXPECT_EQ(run_bounce(args, &err), 2) << args;
        EXPECT_NE(err.find(expect), std::string::npos) << args << " -> " << err;
        EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
    };
    std::string out = " -o " + d.file("x.exr");
    check("render /no/such/scene.json" + out, "/no/such/scene.json: error: file not found");
    check("render " + test::cornell_scene() + out + " --res 0x5", "/camera/resolution/0");
    check("render " + test::cornell_scene() + out + " --res big", "--res big");
    check("render " + test::cornell_scene() + out + " --crop 1,2,3", "--crop");
    check("render " + test::cornell_scene() + out + " --crop 10,5,0,8", "/render/crop");
    check("render " + test::cornell_scene() + out + " --set camera.fov=wide", "--set camera.fov=wide (/camera/fov)");
    check("render " + test::cornell_scene() + out + " --spp 0", "/render/spp");
    check("render " + test::cornell_scene() + out + " --threads abc", "--threads");
    std::string garbage = d.write("garbage.exr", "this is not an EXR file");
    check("render " + test::cornell_scene() + out + " --deep-in " + garbage, "garbage.exr");
    // A camera that looks away from everything.
    check("render " + test::cornell_scene() + out + " --set camera.look_at=[278,273,-2000]", "sees no geometry");
    EXPECT_FALSE(std::filesystem::exists(d.file("x.exr")));
}

TEST(Cli, FailedRenderLeavesAnExistingOutputUntouched) {
    test::TempDir d;
    std::string out = d.write("keep.exr", "previous render");
    std::string garbage = d.write("bad.exr", "not deep");
    EXPECT_EQ(run_bounce("render " + test::cornell_scene() + " -o " + out + " --deep-in " + garbage), 2);
    EXPECT_EQ(read_file(out), "previous render");
}

TEST(Cli, DeepFileFromAnotherSceneIsRefused) {
    test::TempDir d;
    std::string deep = d.file("deep.exr");
    ASSERT_EQ(run_bounce("render " + test::cornell_scene() + " -o " + d.file("a.exr") + " --res 16x16 --spp 1 -q --deep-out " + deep), 0);
    std::string err;
    EXPECT_EQ(
        run_bounce("render " + test::cornell_scene() + " -o " + d.file("b.exr") + " --res 16x16 --set camera.fov=50 -q --deep-in " + deep,
                   &err),
        2);
    EXPECT_NE(err.find("another scene or camera"), std::string::npos) << err;
}

TEST(Cli, TheReadmesLightersLoopReshadesALightEditWithTheCache) {
    // docs/usage.md, "the lighter's loop": a light edit re-shades a region with the frame's cache
    // (its bounce light is the old lights', and bounce says so); moved objects are refused.
    test::TempDir d;
    const std::string scene = test::source_dir() + "/scenes/cornell/glossy-bump.json";
    const std::string common = " --gi cache --res 48x48 --rays 32 --deep-in " + d.file("f.deep.exr") + " --cache-in " + d.file("f.bic");
    ASSERT_EQ(run_bounce("render " + scene + " -o " + d.file("full.exr") + " --gi cache --res 48x48 --rays 32 -q --deep-out " +
                         d.file("f.deep.exr") + " --cache-out " + d.file("f.bic")),
              0);
    std::string err;
    EXPECT_EQ(run_bounce("render " + scene + " -o " + d.file("crop.exr") + common + " --crop 8,40,8,40 --base " + d.file("full.exr") +
                             " --set lights.0.intensity=2",
                         &err),
              0)
        << err;
    EXPECT_NE(err.find("f.bic: lights or materials differ from the cache's"), std::string::npos) << err;
    EXPECT_EQ(run_bounce("render " + scene + " -o " + d.file("same.exr") + common, &err), 0) << err;
    EXPECT_EQ(err.find("differ"), std::string::npos) << err;
    EXPECT_EQ(run_bounce("render " + scene + " -o " + d.file("other.exr") + " --gi cache --res 48x48 --rays 32 --cache-in " +
                             d.file("f.bic") + " --set objects.3.material=red",
                         &err),
              2);
    EXPECT_NE(err.find("f.bic: scene_fingerprint: error: cache was made for another scene (its objects differ"), std::string::npos) << err;
}

TEST(Cli, HelpAndVersionSucceed) {
    EXPECT_EQ(run_bounce("--help"), 0);
    EXPECT_EQ(run_bounce("--version"), 0);
    EXPECT_EQ(run_bounce("render"), 2);
}

// Issue 65: the scene's load, its mesh files' parse and the radiosity layout are phases of the
// statistics (they were most of a big scene's wall time, and invisible).
TEST(Cli, TheStatisticsTimeTheLoadTheMeshParseAndTheRadiosityLayout) {
    test::TempDir d;
    ASSERT_EQ(run_bounce("render " + test::cornell_scene() + " -o " + d.file("o.exr") +
                         " --res 16x16 --spp 1 --gi cache --rays 16 -q --stats-json " + d.file("s.json")),
              0);
    const nlohmann::json phases = nlohmann::json::parse(test::bytes_of(d.file("s.json")))["phases_s"];
    for (const char* p : {"scene load", "mesh parse", "radiosity layout"}) {
        ASSERT_TRUE(phases.contains(p)) << p << " in " << phases.dump();
        EXPECT_GE(phases[p].get<double>(), 0.0) << p;
    }
    EXPECT_GT(phases["mesh parse"].get<double>(), 0.0);  // the box's blocks are OBJ files
}

}  // namespace
}  // namespace bounce
