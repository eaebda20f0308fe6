// Hostile cache files and the cache tools: records beyond range, caches of other settings, tools
// writing only the kind of file they make, inputs edited under a cache.
#include <gtest/gtest.h>

#include "hostile/hostile_util.h"

namespace bounce {
namespace {

using namespace hostile;  // json, fs, expect_refused and the shared scenes

TEST(HostileOutputs, EditingAFileTheSceneReadsInvalidatesItsDeepFileAndCache) {
    test::TempDir d;
    const std::string scene = cornell_copy(d);
    const std::string keep = " --gi cache --deep-out " + d.file("f.deep.exr") + " --cache-out " + d.file("f.bic");
    ASSERT_EQ(test::run_bounce(quick(scene, d.file("a.exr")) + keep), 0);
    // Move one vertex of the mesh: same JSON, other geometry.
    std::string obj = test::bytes_of(d.file("CornellBox-Original.obj"));
    const auto at = obj.find("\nv ");
    obj.insert(at + 3, "0.01");
    obj.erase(at + 7, 1);  // keep the line well-formed: "v 0.01..." replaces the first digit run's start
    std::ofstream(d.file("CornellBox-Original.obj"), std::ios::binary) << obj;
    test::expect_refused(quick(scene, d.file("b.exr")) + " --deep-in " + d.file("f.deep.exr"), {"f.deep.exr", "has changed"});
    test::expect_refused(quick(scene, d.file("b.exr")) + " --gi cache --cache-in " + d.file("f.bic"), {"f.bic", "has changed"});
}

TEST(HostileOutputs, MergingCachesOfOtherSettingsIsRefusedNamingEachKey) {
    test::TempDir d;
    ASSERT_EQ(test::run_bounce(quick(test::cornell_scene(), d.file("a.exr")) + " --gi cache --rays 16 --cache-out " + d.file("a.bic")), 0);
    ASSERT_EQ(test::run_bounce(quick(test::cornell_scene(), d.file("b.exr")) + " --gi cache --rays 32 --min-spacing 3 --cache-out " +
                               d.file("b.bic")),
              0);
    test::expect_refused("cache merge " + d.file("a.bic") + " " + d.file("b.bic") + " -o " + d.file("m.bic"),
                         {"b.bic", "render.rays: 16 -> 32", "render.min_spacing"});
    EXPECT_FALSE(fs::exists(d.file("m.bic")));
    EXPECT_EQ(test::run_bounce("cache merge --force " + d.file("a.bic") + " " + d.file("b.bic") + " -o " + d.file("m.bic")), 0);
}

TEST(HostileOutputs, CacheToolsWriteOnlyTheKindOfFileTheyMake) {
    // `cache export cb.bic -o cb.json` overwrote the scene with a PLY.
    test::TempDir d;
    const std::string scene = d.write("cb.json", test::bytes_of(test::cornell_scene()));
    for (const char* f : {"short_block.obj", "tall_block.obj"})
        std::filesystem::copy_file(test::source_dir() + "/scenes/cornell/" + f, d.file(f));
    ASSERT_EQ(test::run_bounce("render " + scene + " -q --res 16x16 --gi cache --rays 16 -o " + d.file("cb.exr") + " --cache-out " +
                               d.file("cb.bic")),
              0);
    const std::string before = test::bytes_of(scene);
    expect_refused("cache export " + d.file("cb.bic") + " -o " + scene,
                   {"-o " + scene, "the exported point cloud is written as a .ply file"});
    expect_refused("cache filter " + d.file("cb.bic") + " --sphere 0,0,0,1 -o " + scene, {"the filtered cache is written as a .bic file"});
    expect_refused("cache merge " + d.file("cb.bic") + " " + d.file("cb.bic") + " -o " + d.file("cb.exr"),
                   {"the merged cache is written as a .bic file"});
    EXPECT_EQ(test::bytes_of(scene), before);
    EXPECT_EQ(test::run_bounce("cache export " + d.file("cb.bic") + " -o " + d.file("cb.PLY")), 0);
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

}  // namespace
}  // namespace bounce
