// Issue 48: the lighting tool's frame slider steps a shot as `bounce render --frames` does: the
// same plans from the same kept state (records, their hits and refinement's gathers, BVHs,
// radiosity texels), so frame 2 after frame 1 is the sequence's frame 2 bit for bit, with the
// same statistics; every frame's cache is kept for the 3D view's cache-sequence slider.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>

#include "bounce/cache/cache_file.h"
#include "bounce/core/image.h"
#include "bounce/core/stats.h"
#include "test_util.h"
#include "tool_util.h"

namespace bounce {
namespace {

using nlohmann::json;

/// Shot B (a sphere rolling across the Cornell box under a sliding light), small.
SessionOptions rolling_shot(const test::TempDir& d) {
    SessionOptions o;
    o.scene = test::source_dir() + "/scenes/shots/cornell-rolling.json";
    o.out_dir = d.file("out");
    o.threads = 2;
    o.sets = {"camera.resolution=[40,40]", "render.spp=1", "render.rays=48", "render.light_samples=2"};
    return o;
}

/// The CLI's --frames with the session's settings (its --set edits and the defaults it adds).
std::string cli_frames(const SessionOptions& o, const test::TempDir& d, const std::string& frames) {
    std::string args = "render " + o.scene + " -q --threads 2 --gi cache --set render.light_parts=true --frames " + frames;
    for (const std::string& s : o.sets) args += " --set " + s;
    return args + " -o " + d.file("s.####.exr") + " --stats-json " + d.file("s.####.json");
}

void wait_done(LightingSession& s) {
    s.wait();
    ASSERT_EQ(s.status()["state"], "done") << s.status()["message"];
}

/// The statistics that say what a frame kept, moved and gathered.
constexpr const char* kRecordStats[] = {"records",          "records_new",      "records_kept", "records_moved", "records_regathered",
                                        "records_reshaded", "refined_fragments"};

TEST(LightingToolShot, FrameTwoAfterFrameOneIsTheSequencesFrameTwoWithItsStatistics) {
    test::TempDir d;
    const SessionOptions o = rolling_shot(d);
    LightingSession s(o);
    test::render_and_wait(s, SessionAction::Rasterize);
    s.set_frame(2);
    wait_done(s);
    ASSERT_EQ(test::run_bounce(cli_frames(o, d, "1-2")), 0);
    const Image seq = read_exr(d.file("s.0002.exr"));
    EXPECT_EQ(test::differing_values(s.image(), seq), 0u);
    const json tool = s.status()["stats"], cli = json::parse(test::bytes_of(d.file("s.0002.json")));
    for (const char* key : kRecordStats) {
        ASSERT_TRUE(cli.contains(key)) << key;
        EXPECT_EQ(tool[key], cli[key]) << key;
    }
    EXPECT_EQ(tool["rays"]["gather"], cli["rays"]["gather"]);
    std::printf("frame 2: %s records, %s new, %s kept, %s moved, %s regathered, %s reshaded\n", tool["records"].dump().c_str(),
                tool["records_new"].dump().c_str(), tool["records_kept"].dump().c_str(), tool["records_moved"].dump().c_str(),
                tool["records_regathered"].dump().c_str(), tool["records_reshaded"].dump().c_str());
    // The step kept records: far fewer gathered than the frame holds (it re-gathered 98 % before).
    EXPECT_LT(tool["records_new"].get<double>() + tool["records_regathered"].get<double>(), 0.5 * tool["records"].get<double>());
}

TEST(LightingToolShot, EveryFrameLeavesItsCacheAndTheRecordsShownAreTheCurrentFrames) {
    test::TempDir d;
    LightingSession s(rolling_shot(d));
    test::render_and_wait(s, SessionAction::Rasterize);
    s.set_frame(2);
    wait_done(s);
    s.set_frame(3);
    wait_done(s);
    const json files = s.cache_files();
    for (const char* name : {"session.0001.bic", "session.0002.bic", "session.0003.bic"})
        EXPECT_NE(std::find(files.begin(), files.end(), name), files.end()) << name << " in " << files.dump();
    // The view's records are frame 3's: its count is its cache file's, stamped with its frame.
    const ViewArrays shown = s.records("", 1000000);
    const CacheFile three = read_cache_file(d.file("out/session.0003.bic"));
    EXPECT_EQ(shown.meta["count"], three.records.size());
    EXPECT_EQ(shown.meta["frame"], 3);
    EXPECT_EQ(s.status()["stats"]["records"], three.records.size());
    // An earlier frame's cache is its own.
    EXPECT_EQ(s.records("session.0001.bic", 1000000).meta["frame"], 1);
}

// Issue 65: a frame reached by a jump is the farm's frame, forward (the frames in between are
// rendered first) and back (the sequence replayed from its first frame), and going back leaves
// every frame's cache as the sequence made it.
TEST(LightingToolShot, AFrameReachedByAJumpForwardOrBackIsTheSequencesFrame) {
    test::TempDir d;
    const SessionOptions o = rolling_shot(d);
    LightingSession s(o);
    test::render_and_wait(s, SessionAction::Rasterize);
    ASSERT_EQ(test::run_bounce(cli_frames(o, d, "1-4") + " --cache-out " + d.file("s.####.bic")), 0);
    const auto same_cache = [&](int frame) {
        EXPECT_EQ(test::bytes_of(d.file(fmt::format("out/session.{:04}.bic", frame))),
                  test::bytes_of(d.file(fmt::format("s.{:04}.bic", frame))))
            << "frame " << frame << "'s cache";
    };
    const auto same_frame = [&](int frame) {  // the frame shown
        same_cache(frame);
        const Image seq = read_exr(d.file(fmt::format("s.{:04}.exr", frame)));
        EXPECT_EQ(test::differing_values(s.image(), seq), 0u) << "frame " << frame;
        const json tool = s.status()["stats"], cli = json::parse(test::bytes_of(d.file(fmt::format("s.{:04}.json", frame))));
        for (const char* key : kRecordStats) EXPECT_EQ(tool[key], cli[key]) << key << " of frame " << frame;
    };
    EXPECT_EQ(s.set_frame(4)["from"], 2);  // frames 2 and 3 first
    wait_done(s);
    EXPECT_EQ(s.status()["frame"], 4);
    same_frame(4);
    same_cache(3);                         // the frame in between is the sequence's too
    EXPECT_EQ(s.set_frame(2)["from"], 1);  // back: the sequence again from frame 1
    wait_done(s);
    same_frame(2);
    same_cache(4);   // frame 4's cache was left as the sequence made it
    s.set_frame(3);  // and a step from there is the next frame
    wait_done(s);
    same_frame(3);
}

TEST(LightingToolShot, AFrameIsAWholeNumberInsideTheShot) {
    test::TempDir d;
    LightingSession s(rolling_shot(d));
    for (double bad : {2.5, 0.0, 49.0, -1.0}) EXPECT_THROW(s.set_frame(bad), InputError) << bad;
}

TEST(LightingToolShot, AnEditOfAnObjectsGeometryAsksForANewDeepFile) {
    test::TempDir d;
    LightingSession s(test::small_session(d));
    test::render_and_wait(s, SessionAction::Rasterize);
    // The short block (objects.6, a mesh) as a subdivision surface; the floor's fine tessellation.
    EXPECT_EQ(s.edit("objects.6.subdivision", "catmull-clark")["needs"], "rasterize");
    EXPECT_EQ(s.pending(), SessionAction::Rasterize);
    test::render_and_wait(s, s.pending());
    EXPECT_EQ(s.edit("objects.0.fine_subdivisions", 1)["needs"], "rasterize");
    // A light's edit still needs only a re-shade.
    EXPECT_EQ(s.edit("materials.white.color", json::array({0.5, 0.5, 0.5}))["needs"], "reshade");
    EXPECT_EQ(s.pending(), SessionAction::Rasterize);
    // The render the edits ask for succeeds (it failed on the deep file of another scene).
    test::render_and_wait(s, s.pending());
}

TEST(LightingToolShot, TheFirstRenderSaysItMadeTheDeepFile) {
    test::TempDir d;
    LightingSession s(test::small_session(d));
    s.start(s.pending());
    wait_done(s);
    EXPECT_EQ(s.status()["action"], "rasterize");
}

}  // namespace
}  // namespace bounce
