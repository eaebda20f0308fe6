// The frame as a plan: which passes plan_frame chooses for each request, and that run_frame
// does what the plan says (a re-shade of a complete cache gathers nothing; of an incomplete
// one, only where records are missing).
#include <gtest/gtest.h>

#include "bounce/core/communicator.h"
#include "bounce/core/error.h"
#include "bounce/render/render.h"
#include "test_util.h"

namespace bounce {
namespace {

Scene cornell(std::vector<Override> extra = {}) {
    std::vector<Override> o = {"camera.resolution=[40,40]", "render.spp=1", "render.gi=\"cache\"", "render.rays=64",
                               "render.light_samples=2"};
    o.insert(o.end(), extra.begin(), extra.end());
    return load_scene(test::cornell_scene(), o);
}

TEST(FramePlan, AStillTracesGathersIntoAnEmptyCacheAndRefines) {
    const FramePlan p = plan_frame(cornell(), {}, {});
    EXPECT_EQ(p.visibility, VisibilityStep::Trace);
    EXPECT_EQ(p.cache, CacheStart::Empty);
    EXPECT_EQ(p.gather, GatherStep::Cache);
    EXPECT_EQ(p.radiosity, RadiosityStep::Bake);
    EXPECT_TRUE(p.refine);  // render.refine defaults to 0.1
    EXPECT_EQ(p.window, (std::array<int, 4>{0, 40, 0, 40}));
    EXPECT_EQ(p.gather_window, p.window);
}

TEST(FramePlan, BruteForceAndDirectLightHaveNoCache) {
    EXPECT_EQ(plan_frame(cornell({"render.gi=\"brute\""}), {}, {}).gather, GatherStep::Brute);
    EXPECT_EQ(plan_frame(cornell({"render.gi=\"brute\""}), {}, {}).cache, CacheStart::None);
    const FramePlan direct = plan_frame(cornell({"render.gi=\"none\""}), {}, {});
    EXPECT_EQ(direct.gather, GatherStep::None);
    EXPECT_EQ(direct.radiosity, RadiosityStep::None);
    // AO gathers need no radiosity textures.
    EXPECT_EQ(plan_frame(cornell({"render.ao=true"}), {}, {}).radiosity, RadiosityStep::None);
}

TEST(FramePlan, ACropGathersAMarginAndARegatherFlushesOnlyInsideIt) {
    RenderRequest req;
    req.cache_in = "f.bic", req.kind = FrameKind::Regather;
    const FramePlan p = plan_frame(cornell({"render.crop=[10,20,12,30]"}), {}, req);
    const int m = crop_margin(cornell());
    EXPECT_EQ(p.gather_window, (std::array<int, 4>{0, std::min(40, 20 + m), 0, std::min(40, 30 + m)}));
    EXPECT_EQ(p.cache, CacheStart::File);
    EXPECT_TRUE(p.flush_crop);
    // Without a crop, a re-gather starts from nothing.
    EXPECT_EQ(plan_frame(cornell(), {}, req).cache, CacheStart::Empty);
}

TEST(FramePlan, AReshadeStartsFromWhatThePreviousFrameLeftAndGathersOnlyWhereMissing) {
    Stats s;
    RenderResult first = render(cornell(), {}, s, nullptr);
    const FrameState state = first.release_state();
    RenderRequest req;
    req.kind = FrameKind::Reshade;
    const FramePlan p = plan_frame(cornell(), state, req);
    EXPECT_EQ(p.visibility, VisibilityStep::Previous);
    EXPECT_EQ(p.cache, CacheStart::Previous);
    EXPECT_EQ(p.gather, GatherStep::WhereMissing);
    // Nothing missing: no ray is traced, no record made, the image is the first frame's.
    Stats s2;
    RenderResult again = run_frame(cornell(), p, state, req, s2, nullptr);
    EXPECT_FALSE(again.gathered);
    EXPECT_FALSE(again.cache_changed());
    EXPECT_EQ(again.shading_misses, 0u);
    EXPECT_EQ(s2.total().gather_rays, 0u);
    EXPECT_EQ(s2.total().camera_rays, 0u);
    EXPECT_EQ(again.cache->size(), state.cache->size());
    Stats s3;
    RenderResult fresh = render(cornell(), {}, s3, nullptr);
    EXPECT_TRUE(again.image.find("indirect")->data == fresh.image.find("indirect")->data);
    EXPECT_EQ(s2.to_json()["plan"]["gather"], "only where records are missing");
}

TEST(FramePlan, AReshadeOfAnIncompleteCacheGathersWhereItMissesAndMissesNothing) {
    Stats s;
    // The previous frame covered only a crop: the rest of the frame has no records.
    RenderResult crop = render(cornell({"render.crop=[0,12,0,12]"}), {}, s, nullptr);
    RenderResult full = render(cornell({"render.gi=\"none\""}), {}, s, nullptr);
    FrameState state;
    state.deep = std::make_shared<const DeepBuffer>(full.deep);
    state.cache = std::shared_ptr<const IrradianceCache>(std::move(crop.cache));
    RenderRequest req;
    req.kind = FrameKind::Reshade;
    Stats s2;
    const FramePlan p = plan_frame(cornell(), state, req);
    RenderResult r = run_frame(cornell(), p, state, req, s2, nullptr);
    EXPECT_TRUE(r.gathered);
    EXPECT_GT(r.records_new, 0u);
    EXPECT_EQ(r.records_loaded, state.cache->size());
    EXPECT_EQ(r.cache->size(), r.records_loaded + r.records_new);
    EXPECT_EQ(r.shading_misses, 0u);
    EXPECT_TRUE(r.cache_changed());
}

TEST(FramePlan, AReshadeWithAStaleDeepBufferSaysSo) {
    Stats s;
    RenderResult first = render(cornell(), {}, s, nullptr);
    const FrameState state = first.release_state();
    RenderRequest req;
    req.kind = FrameKind::Reshade;
    const Scene moved = cornell({"camera.fov=30"});
    try {
        run_frame(moved, plan_frame(moved, state, req), state, req, s, nullptr);
        FAIL() << "a deep buffer of another camera was shaded";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("another scene or camera"), std::string::npos) << e.what();
    }
}

}  // namespace
}  // namespace bounce

namespace bounce {
namespace {

/// Rank 0 of two, for plans only (a plan asks how many processes there are, never exchanges).
class TwoRanks : public SingleProcess {
  public:
    int size() const override { return 2; }
};

TEST(FramePlan, RefinementsGathersAreKeptForReprojectionInAShot) {
    RenderRequest shot;
    shot.kind = FrameKind::ShotFrame;
    EXPECT_TRUE(plan_frame(cornell(), {}, shot).keep_gathers);  // on by default
    EXPECT_FALSE(plan_frame(cornell(), {}, {}).keep_gathers);   // a still has no next frame
    EXPECT_FALSE(plan_frame(cornell({"render.temporal_refine_reuse=0"}), {}, shot).keep_gathers);
    // An MPI job's processes all hold every gather's hits (refinement_pass): each reuses what
    // one process would (Mpi.AMovingCamerasShotReprojectsTheSameGathersAtAnyRankCount).
    TwoRanks two;
    shot.comm = &two;
    EXPECT_TRUE(plan_frame(cornell(), {}, shot).keep_gathers);
}

TEST(FramePlan, EveryDecisionIsAStepOfThePlanAndDescribed) {
    // Mirror and glass paths to the sites gathers light: only with specular materials, and only
    // when gathers light them.
    const Scene mirrors =
        load_scene(test::source_dir() + "/scenes/cornell/mirror-glass.json", {"camera.resolution=[40,40]", "render.gi=\"cache\""});
    EXPECT_TRUE(plan_frame(mirrors, {}, {}).specular_sites);
    EXPECT_FALSE(plan_frame(cornell(), {}, {}).specular_sites);
    EXPECT_EQ(plan_frame(mirrors, {}, {}).describe()["specular_sites"], true);
    // Ranks exchange radiosity sides only when the textures outlive the frame (a shot's next frame).
    RenderRequest shot;
    shot.kind = FrameKind::ShotFrame;
    TwoRanks two;
    shot.comm = &two;
    EXPECT_TRUE(plan_frame(cornell(), {}, shot).share_radiosity);
    RenderRequest still;
    still.comm = &two;
    EXPECT_FALSE(plan_frame(cornell(), {}, still).share_radiosity);
    EXPECT_EQ(plan_frame(cornell(), {}, shot).describe()["share_radiosity"], true);
    // What ranks cannot make together is refused while planning, before any pass.
    EXPECT_THROW(plan_frame(cornell({"render.light_parts=true"}), {}, still), InputError);
}

TEST(FramePlan, ASequenceIsNotGatheredAnewFrameByFrame) {
    test::expect_refused(
        "render " + test::source_dir() + "/scenes/shots/cornell-rolling.json --frames 1-2 --regather -o /tmp/never.####.exr",
        {"--regather", "--frame"});
}

}  // namespace
}  // namespace bounce
