// Issue 29, what a render may destroy and when it says no: outputs that would overwrite a file
// the scene reads, a kill mid-render, checks that came after the work, identities that missed
// an edited file, merges and comparisons that passed wrong data, memory limits and messages.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <thread>

#include "bounce/cache/cache_file.h"
#include "bounce/core/image.h"
#include "test_util.h"

namespace bounce {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

/// A scene of the OBJ + MTL Cornell box, copied into `d` (so tests may edit its files).
std::string cornell_copy(const test::TempDir& d) {
    for (const auto& e : fs::directory_iterator(test::source_dir() + "/tests/data/cornell_box"))
        fs::copy_file(e.path(), d.path() / e.path().filename(), fs::copy_options::overwrite_existing);
    const json j = {{"camera", {{"position", {0, 1, 3.5}}, {"look_at", {0, 1, 0}}, {"fov", 40}}},
                    {"objects", {{{"type", "mesh"}, {"file", "CornellBox-Original.obj"}}}},
                    {"lights", {{{"type", "point"}, {"position", {0, 1.5, 0}}}}}};
    return d.write("cornell.json", j.dump());
}

std::string quick(const std::string& scene, const std::string& out) {
    return "render " + scene + " -o " + out + " -q --res 16x16 --spp 1 --light-samples 1";
}

TEST(HostileOutputs, NoOutputMayOverwriteAFileTheSceneReads) {
    test::TempDir d;
    const std::string scene = cornell_copy(d);
    const std::string mesh = d.file("CornellBox-Original.obj"), mtl = d.file("CornellBox-Original.mtl");
    const std::string before = test::bytes_of(mesh), mtl_before = test::bytes_of(mtl);
    const std::string out = " -o " + d.file("o.exr");
    test::expect_refused(quick(scene, d.file("o.exr")) + " --gi cache --cache-out " + mesh, {"CornellBox-Original.obj", "names an input"});
    test::expect_refused(quick(scene, d.file("o.exr")) + " --stats-json " + mesh, {"CornellBox-Original.obj", "names an input"});
    test::expect_refused(quick(scene, d.file("o.exr")) + " --deep-out " + mtl, {"CornellBox-Original.mtl", "names an input"});
    EXPECT_EQ(test::bytes_of(mesh), before);
    EXPECT_EQ(test::bytes_of(mtl), mtl_before);
    // A texture and a displacement map, and a file inside the radiosity folder.
    json j = test::base_scene();
    j["materials"] = {{"m", {{"color_texture", "tex.exr"}}}};
    j["objects"][0]["material"] = "m";
    test::write_constant_image(d.file("tex.exr"), 4, 4, 3, 0.5f);
    const std::string tex_before = test::bytes_of(d.file("tex.exr"));
    d.write("t.json", j.dump());
    test::expect_refused("render " + d.file("t.json") + " -q -o " + d.file("tex.exr"), {"tex.exr", "names an input"});
    test::expect_refused(quick(d.file("t.json"), d.file("o.exr")) + " --deep-out " + d.file("tex.exr"), {"tex.exr", "names an input"});
    EXPECT_EQ(test::bytes_of(d.file("tex.exr")), tex_before);
    fs::create_directory(d.file("rad"));
    test::expect_refused(quick(d.file("t.json"), d.file("rad/o.exr")) + " --gi brute --radiosity-textures " + d.file("rad"),
                         {"rad/o.exr", "inside"});
}

TEST(HostileOutputs, AKilledRenderLeavesEveryOutputOfThePreviousRun) {
    test::TempDir d;
    const std::string files = fmt::format(" -o {} --deep-out {} --cache-out {} --stats-json {}", d.file("f.exr"), d.file("f.deep.exr"),
                                          d.file("f.bic"), d.file("f.json"));
    const std::string scene = test::cornell_scene();
    ASSERT_EQ(test::run_bounce("render " + scene + " -q --res 24x24 --spp 1 --gi cache --rays 16" + files), 0);
    std::vector<std::string> before;
    for (const char* f : {"f.exr", "f.png", "f.deep.exr", "f.bic", "f.json"}) before.push_back(test::bytes_of(d.file(f)));
    // The same outputs from a render that takes far longer than the kill's delay (after visibility).
    for (int delay_ms : {300, 1200}) {
        const pid_t pid = fork();
        if (pid == 0) {
            const std::string cmd = std::string(BOUNCE_BINARY) + " render " + scene +
                                    " -q --res 256x256 --spp 4 --gi brute --rays 4096 --seed 7 --stats-json " + d.file("f.json") + " -o " +
                                    d.file("f.exr") + " --deep-out " + d.file("f.deep.exr") + " 2>/dev/null";
            execl("/bin/sh", "sh", "-c", ("exec " + cmd).c_str(), static_cast<char*>(nullptr));
            _exit(127);
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms));
        kill(pid, SIGKILL);
        int status = 0;
        waitpid(pid, &status, 0);
        ASSERT_TRUE(WIFSIGNALED(status)) << "the render finished before the kill: make it slower";
        size_t i = 0;
        for (const char* f : {"f.exr", "f.png", "f.deep.exr", "f.bic", "f.json"}) EXPECT_EQ(test::bytes_of(d.file(f)), before[i++]) << f;
    }
}

TEST(HostileOutputs, FlagsThatCannotWorkAreRefusedBeforeTheRender) {
    test::TempDir d;
    // A scene whose render would fail at visibility: a check made after the work would say that.
    json j = test::base_scene();
    j["camera"]["look_at"] = {0, 20, 5};
    d.write("up.json", j.dump());
    const std::string scene = d.file("up.json"), out = d.file("o.exr");
    d.write("base.bic", "x");
    test::expect_refused(quick(scene, d.file("base.bic") + "/x.exr"), {"base.bic", "not a folder"});
    test::expect_refused(quick(scene, "/proc/x.exr"), {"/proc/x.exr", "cannot create a file"});
    test::expect_refused(quick(scene, out) + " --gi cache --cache-out /proc/c.bic", {"/proc/c.bic", "cannot create a file"});
    test::expect_refused(quick(scene, out) + " --show bogus", {"--show bogus", "no layer"});
    test::expect_refused(quick(scene, out) + " --radiosity-textures " + d.file("base.bic"), {"/render/radiosity_textures", "not a folder"});
    test::expect_refused(quick(scene, d.file("o.####.exr")) + " --gi cache --frames 1-2 --cache-out " + d.file("c.bic"),
                         {"--cache-out", "#### frame pattern"});
    EXPECT_FALSE(fs::exists(out));
    // --show of a one-channel layer writes its PNG (it used to end in "internal error").
    for (const char* layer : {"ao", "depth", "refined", "N"})
        EXPECT_EQ(test::run_bounce(quick(test::cornell_scene(), out) + " --gi cache --show " + layer), 0) << layer;
}

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

TEST(HostileOutputs, CompareBaseAndBakeAoRefuseWhatWouldMislead) {
    test::TempDir d;
    const std::string cornell = test::cornell_scene();
    ASSERT_EQ(test::run_bounce(quick(cornell, d.file("a.exr"))), 0);
    Image nan = read_exr(d.file("a.exr"));
    for (Layer& l : nan.layers) std::fill(l.data.begin(), l.data.end(), NAN);
    write_exr(d.file("nan.exr"), nan);
    test::expect_refused("compare " + d.file("a.exr") + " " + d.file("nan.exr"), {"nan.exr", "not finite"});
    // A base rendered from another camera would paste a crop onto another picture.
    ASSERT_EQ(test::run_bounce(quick(cornell, d.file("other.exr")) + " --set camera.fov=30"), 0);
    test::expect_refused(quick(cornell, d.file("c.exr")) + " --crop 0,8,0,8 --base " + d.file("other.exr"),
                         {"other.exr", "another scene or camera"});
    EXPECT_EQ(test::run_bounce(quick(cornell, d.file("c.exr")) + " --crop 0,8,0,8 --base " + d.file("a.exr")), 0);
    const std::string displaced = test::source_dir() + "/scenes/displaced/displaced.json";
    for (const char* distance : {"nan", "0", "-1"})
        test::expect_refused(
            fmt::format("bake-ao {} --object rounded_cube --res 8 --rays 4 -o {} --distance {}", displaced, d.file("ao.exr"), distance),
            {"--distance", "a number in (0, 1e+18]"});
    test::expect_refused(fmt::format("bake-ao {} --object rounded_cube --res 8 --rays 4 -o /proc/ao.exr", displaced),
                         {"/proc/ao.exr", "cannot create"});
}

TEST(HostileOutputs, WhatCannotFitUnderAnAddressSpaceLimitIsRefusedWithItsEstimate) {
    // A sanitizer reserves terabytes of shadow address space at start, so no sanitized binary
    // can start under ulimit -v; the plain build runs this test.
#if defined(__SANITIZE_THREAD__) || defined(__SANITIZE_ADDRESS__)
    GTEST_SKIP() << "a sanitizer's shadow memory cannot start under an address-space limit";
#endif
    test::TempDir d;
    // ulimit -v 2000000 (about 1.9 GiB): fur at 3e7 strands (10.7 GiB, inside the 16 GiB budget)
    // and bake-ao --res 12000 ended in std::bad_alloc; both are refused with the estimate.
    json j = test::base_scene();
    j["objects"][0]["fur"] = {{"count", 30000000}, {"length", 0.1}};
    d.write("fur.json", j.dump());
    const auto under_limit = [&](const std::string& args) {
        std::string err;
        const int rc = test::run_bounce_shell("ulimit -v 2000000; exec " + std::string(BOUNCE_BINARY) + " " + args, &err);
        return std::pair{rc, err};
    };
    auto [rc, err] = under_limit(quick(d.file("fur.json"), d.file("o.exr")));
    EXPECT_EQ(rc, 2) << err;
    EXPECT_NE(err.find("/objects/0/fur/count"), std::string::npos) << err;
    EXPECT_NE(err.find("it may use"), std::string::npos) << err;  // the budget and what is available differ
    EXPECT_NE(err.find("GiB available)"), std::string::npos) << err;
    const std::string displaced = test::source_dir() + "/scenes/displaced/displaced.json";
    std::tie(rc, err) = under_limit(fmt::format("bake-ao {} --object rounded_cube --res 12000 -o {}", displaced, d.file("ao.exr")));
    EXPECT_EQ(rc, 2) << err;
    EXPECT_NE(err.find("--res 12000"), std::string::npos) << err;
    // Issue 65: 10^6 placements (3.3 KB each at render) were "out of memory" with no file or
    // estimate, and a scene file of 10^7 aborted in its parse: both refused with the estimate.
    j = test::base_scene();
    j["objects"].push_back({{"name", "ball"}, {"type", "sphere"}, {"center", {0, 0, 0}}, {"radius", 1}, {"prototype", true}});
    std::string rows;
    for (int i = 0; i < 1000000; ++i) rows += fmt::format("{}{{\"translate\":[{},{},{}]}}", i ? "," : "", i % 1000, i / 1000, 0);
    std::string text = j.dump();
    text.insert(text.rfind(']'), R"(,{"name":"row","instances":{"of":"ball","transforms":[)" + rows + "]}}");
    d.write("many.json", text);
    std::tie(rc, err) = under_limit(quick(d.file("many.json"), d.file("o.exr")));
    EXPECT_EQ(rc, 2) << err;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
    EXPECT_NE(err.find("many.json"), std::string::npos) << err;
    EXPECT_NE(err.find("/objects/2/instances/transforms"), std::string::npos) << err;
    EXPECT_NE(err.find("1000000 instances"), std::string::npos) << err;
    // A scene file whose JSON alone cannot be read within the limit.
    std::string huge = text;
    for (int copies = 0; copies < 8; ++copies)
        huge.insert(huge.rfind(']'), R"(,{"name":"more","instances":{"of":"ball","transforms":[)" + rows + "]}}");
    d.write("huge.json", huge);
    std::tie(rc, err) = under_limit(quick(d.file("huge.json"), d.file("o.exr")));
    EXPECT_EQ(rc, 2) << err;
    EXPECT_NE(err.find("huge.json: error: reading its"), std::string::npos) << err;
}

TEST(HostileOutputs, MessagesNameWhatTheUserWrote) {
    test::TempDir d;
    json j = test::base_scene();
    j.erase("lights");
    d.write("dark.json", j.dump());
    test::expect_refused(quick(d.file("dark.json"), d.file("o.exr")) + " --set lights.0.intensity=2",
                         {"command line", "--set lights.0.intensity=2", "no \"lights\" list"});
    test::expect_refused("cache frob", {"cache frob", "unknown command", "valid:"});
    EXPECT_EQ(test::run_bounce(quick(test::cornell_scene(), d.file("o.exr")) + " --rays 1e3 --gi none"), 0);
    test::expect_refused(quick(test::cornell_scene(), d.file("o.exr")) + " --rays 2.5", {"--rays", "expected an integer, got 2.5"});
    // A cache header whose record count is negative is blamed on that count (it printed 2^64 - 1
    // and blamed fragment_record_count). The header is rewritten with a valid checksum.
    ASSERT_EQ(test::run_bounce(quick(test::cornell_scene(), d.file("a.exr")) + " --gi cache --cache-out " + d.file("a.bic")), 0);
    const std::string bytes = test::bytes_of(d.file("a.bic"));
    const std::string bad = test::with_cache_header(bytes, [](json& h) { h["record_count"] = -1; });
    d.write("neg.bic", bad);
    test::expect_refused("cache info " + d.file("neg.bic"), {"neg.bic", "header/record_count", "-1 is not a record count"});
}

}  // namespace
}  // namespace bounce
