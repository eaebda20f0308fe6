// The command line attacked: flags out of range, outputs that would overwrite an input (the
// OpenColorIO config and its LUTs included), FIFOs, killed runs, address-space limits, messages.
#include <gtest/gtest.h>

#include "hostile/hostile_util.h"

namespace bounce {
namespace {

using namespace hostile;  // json, fs, expect_refused and the shared scenes

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

TEST(HostileOutputs, ResumeRendersAgainAFrameWhoseFilesAreCutShort) {
    test::TempDir d;
    const std::string scene = test::source_dir() + "/scenes/shots/cornell-rolling.json";
    const std::string args = "render " + scene + " --res 16x16 --gi cache --rays 16 --frames 1-3 -o " + d.file("s.####.exr") +
                             " --cache-out " + d.file("s.####.bic");
    ASSERT_EQ(test::run_bounce(args + " -q"), 0);
    std::filesystem::resize_file(d.file("s.0002.exr"), 1000);
    std::filesystem::resize_file(d.file("s.0003.bic"), 500);
    std::string err;
    ASSERT_EQ(test::run_bounce(args + " --resume", &err), 0) << err;
    EXPECT_NE(err.find("frame 1: outputs complete, skipped"), std::string::npos) << err;
    EXPECT_EQ(err.find("frame 2: outputs complete"), std::string::npos) << err;
    EXPECT_EQ(err.find("frame 3: outputs complete"), std::string::npos) << err;
    EXPECT_GT(std::filesystem::file_size(d.file("s.0002.exr")), 1000u);
    EXPECT_GT(std::filesystem::file_size(d.file("s.0003.bic")), 500u);
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
