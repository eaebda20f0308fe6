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

/// The plan's steps by name, in order, with " (if missed)" on those that run only where the
/// shading before them missed.
std::vector<std::string> steps(const FramePlan& p) {
    std::vector<std::string> out;
    const nlohmann::json described = p.describe();
    for (const nlohmann::json& s : described["steps"])
        out.push_back(s["step"].get<std::string>() + (s.contains("when") ? " (if missed)" : ""));
    return out;
}
using Names = std::vector<std::string>;

TEST(FramePlan, AStillTracesGathersIntoAnEmptyCacheAndRefines) {
    const FramePlan p = plan_frame(cornell(), {}, {});
    EXPECT_EQ(steps(p),
              (Names{"accel", "visibility", "cache start", "radiosity", "gather records", "refine", "shade", "finish radiosity"}));
    EXPECT_EQ(p.find<AccelStep>()->source, AccelSource::Build);
    EXPECT_EQ(p.find<VisibilityStep>()->source, DeepSource::Trace);
    EXPECT_EQ(p.cache_start(), CacheStart::Empty);
    EXPECT_EQ(p.find<RadiosityStep>()->source, RadiositySource::Bake);
    EXPECT_EQ(p.find<RefineStep>()->rays, 64);  // render.refine defaults to 0.1; refine_rays 0 = render.rays
    EXPECT_EQ(p.find<ShadeStep>()->indirect, IndirectFrom::Cache);
    EXPECT_EQ(p.find<ShadeStep>()->correction_rays, 0);
    EXPECT_EQ(p.window, (std::array<int, 4>{0, 40, 0, 40}));
    EXPECT_EQ(p.gather_window, p.window);
    // Each setting the steps carry is resolved by the plan, not read by the pass.
    const FramePlan q = plan_frame(
        cornell({"render.correction_rays=16", "render.refine_rays=32", "render.min_rays=16", "render.metric=\"hessian\""}), {}, {});
    EXPECT_EQ(q.find<ShadeStep>()->correction_rays, 16);
    EXPECT_EQ(q.find<RefineStep>()->rays, 32);
    EXPECT_EQ(q.find<GatherRecordsStep>()->first_rays, 16);
    EXPECT_TRUE(q.find<GatherRecordsStep>()->hessian);
    EXPECT_EQ(plan_frame(cornell({"render.min_rays=64"}), {}, {}).find<GatherRecordsStep>()->first_rays, 0);  // not fewer than rays
}

TEST(FramePlan, BruteForceAndDirectLightHaveNoCache) {
    const FramePlan brute = plan_frame(cornell({"render.gi=\"brute\""}), {}, {});
    EXPECT_EQ(steps(brute), (Names{"accel", "visibility", "radiosity", "brute force", "shade", "finish radiosity"}));
    EXPECT_EQ(brute.cache_start(), CacheStart::None);
    EXPECT_EQ(brute.find<ShadeStep>()->indirect, IndirectFrom::Brute);
    const FramePlan direct = plan_frame(cornell({"render.gi=\"none\""}), {}, {});
    EXPECT_EQ(steps(direct), (Names{"accel", "visibility", "shade"}));
    EXPECT_EQ(direct.find<ShadeStep>()->indirect, IndirectFrom::None);
    // A cache file given to a render without a cache is read for its records layer only.
    RenderRequest with_file;
    with_file.cache_in = "f.bic";
    EXPECT_EQ(steps(plan_frame(cornell({"render.gi=\"none\""}), {}, with_file)), (Names{"accel", "visibility", "cache start", "shade"}));
    // AO gathers need no radiosity textures.
    EXPECT_EQ(steps(plan_frame(cornell({"render.ao=true"}), {}, {})),
              (Names{"accel", "visibility", "cache start", "gather records", "refine", "shade"}));
}

TEST(FramePlan, ACropGathersAMarginAndARegatherFlushesOnlyInsideIt) {
    RenderRequest req;
    req.cache_in = "f.bic", req.kind = FrameKind::Regather;
    const FramePlan p = plan_frame(cornell({"render.crop=[10,20,12,30]"}), {}, req);
    const int m = crop_margin(cornell().render.cache);
    EXPECT_EQ(p.gather_window, (std::array<int, 4>{0, std::min(40, 20 + m), 0, std::min(40, 30 + m)}));
    EXPECT_EQ(p.cache_start(), CacheStart::File);
    EXPECT_EQ(p.find<CacheStartStep>()->cache_in, "f.bic");
    EXPECT_TRUE(p.find<CacheStartStep>()->flush_crop);
    EXPECT_TRUE(p.find<VisibilityStep>()->crop);
    // Without a crop, a re-gather starts from nothing.
    EXPECT_EQ(plan_frame(cornell(), {}, req).cache_start(), CacheStart::Empty);
    EXPECT_FALSE(plan_frame(cornell(), {}, req).find<CacheStartStep>()->flush_crop);
}

/// What a still of the test's Cornell box leaves for the next plan.
FrameState first_frame_state() {
    Stats s;
    return render(cornell(), {}, s, nullptr).release_state();
}

TEST(FramePlan, AReshadeStartsFromWhatThePreviousFrameLeftAndGathersOnlyWhereMissing) {
    const FrameState state = first_frame_state();
    RenderRequest req;
    req.kind = FrameKind::Reshade;
    const FramePlan p = plan_frame(cornell(), state, req);
    EXPECT_EQ(p.find<VisibilityStep>()->source, DeepSource::Previous);
    EXPECT_EQ(p.cache_start(), CacheStart::Previous);
    // Gathering only where shading missed is a list of steps that run only then.
    EXPECT_EQ(steps(p), (Names{"accel", "visibility", "cache start", "shade", "radiosity (if missed)", "gather records (if missed)",
                               "refine (if missed)", "shade (if missed)", "finish radiosity"}));
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
    EXPECT_EQ(s2.to_json()["plan"]["steps"][5]["step"], "gather records");
    EXPECT_EQ(s2.to_json()["plan"]["steps"][5]["when"], "if shading missed");
    EXPECT_FALSE(s2.to_json().contains("gather_rays_per_s"));  // no gathering step ran
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
    const FrameState state = first_frame_state();
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
    EXPECT_TRUE(plan_frame(cornell(), {}, shot).find<RefineStep>()->keep_gathers);  // on by default
    EXPECT_TRUE(plan_frame(cornell(), {}, shot).find<RefineStep>()->keep_rays);
    EXPECT_FALSE(plan_frame(cornell(), {}, {}).find<RefineStep>()->keep_gathers);  // a still has no next frame
    EXPECT_FALSE(plan_frame(cornell(), {}, {}).find<RefineStep>()->keep_rays);
    EXPECT_FALSE(plan_frame(cornell({"render.temporal_refine_reuse=0"}), {}, shot).find<RefineStep>()->keep_gathers);
    // An MPI job's processes all hold every gather's hits (refinement_pass): each reuses what
    // one process would (Mpi.AMovingCamerasShotReprojectsTheSameGathersAtAnyRankCount).
    TwoRanks two;
    shot.comm = &two;
    EXPECT_TRUE(plan_frame(cornell(), {}, shot).find<RefineStep>()->keep_gathers);
}

TEST(FramePlan, EveryDecisionIsAStepOfThePlanAndDescribed) {
    // Mirror and glass paths to the sites gathers light: only with specular materials, and only
    // when gathers light them.
    const Scene mirrors =
        load_scene(test::source_dir() + "/scenes/cornell/mirror-glass.json", {"camera.resolution=[40,40]", "render.gi=\"cache\""});
    EXPECT_EQ(steps(plan_frame(mirrors, {}, {})), (Names{"accel", "visibility", "cache start", "specular sites", "radiosity",
                                                         "gather records", "refine", "gather sites", "shade", "finish radiosity"}));
    EXPECT_EQ(plan_frame(mirrors, {}, {}).find<ShadeStep>()->sites, SiteLightFrom::Cache);
    EXPECT_FALSE(plan_frame(cornell(), {}, {}).find<SpecularSitesStep>());
    EXPECT_EQ(plan_frame(cornell(), {}, {}).find<ShadeStep>()->sites, SiteLightFrom::None);
    const Scene brute_mirrors =
        load_scene(test::source_dir() + "/scenes/cornell/mirror-glass.json", {"camera.resolution=[40,40]", "render.gi=\"brute\""});
    EXPECT_TRUE(plan_frame(brute_mirrors, {}, {}).find<BruteGatherStep>()->sites);
    EXPECT_EQ(plan_frame(brute_mirrors, {}, {}).find<ShadeStep>()->sites, SiteLightFrom::Brute);
    // Paths to the radiosity textures: the textures are made before any gather or shading, no sites.
    const Scene radiosity_mirrors =
        load_scene(test::source_dir() + "/scenes/cornell/mirror-glass.json",
                   {"camera.resolution=[40,40]", "render.gi=\"cache\"", "render.indirect_at_specular_hits=\"radiosity\""});
    EXPECT_EQ(steps(plan_frame(radiosity_mirrors, {}, {})),
              (Names{"accel", "visibility", "cache start", "radiosity", "gather records", "refine", "shade", "finish radiosity"}));
    EXPECT_EQ(plan_frame(radiosity_mirrors, {}, {}).find<ShadeStep>()->sites, SiteLightFrom::Radiosity);
    // Ranks exchange radiosity sides only when the textures outlive the frame (a shot's next frame).
    RenderRequest shot;
    shot.kind = FrameKind::ShotFrame;
    TwoRanks two;
    shot.comm = &two;
    EXPECT_TRUE(plan_frame(cornell(), {}, shot).find<FinishRadiosityStep>()->share);
    RenderRequest still;
    still.comm = &two;
    EXPECT_FALSE(plan_frame(cornell(), {}, still).find<FinishRadiosityStep>()->share);
    EXPECT_EQ(plan_frame(cornell(), {}, still).find<RadiosityStep>()->source, RadiositySource::BakeSplit);
    EXPECT_EQ(plan_frame(cornell(), {}, shot).describe()["steps"].back()["share"], true);
    // What ranks cannot make together is refused while planning, before any pass.
    EXPECT_THROW(plan_frame(cornell({"render.light_parts=true"}), {}, still), InputError);
}

TEST(FramePlan, TheToolPlansOnceAndWritesItsDeepFileOnlyWhenItTraces) {
    RenderRequest req;
    req.deep_out_if_traced = "session.exr";
    EXPECT_EQ(plan_frame(cornell(), {}, req).deep_out, "session.exr");
    EXPECT_TRUE(plan_frame(cornell(), {}, req).find<VisibilityStep>()->every_tile);  // rank 0 writes it whole
    const FrameState state = first_frame_state();
    req.kind = FrameKind::Reshade;
    const FramePlan again = plan_frame(cornell(), state, req);
    EXPECT_EQ(again.find<VisibilityStep>()->source, DeepSource::Previous);
    EXPECT_EQ(again.deep_out, "");  // its file is on disk already
    EXPECT_FALSE(again.find<VisibilityStep>()->every_tile);
    req.deep_out = "asked.exr";  // a file the front end asks for is written however the buffer came
    EXPECT_EQ(plan_frame(cornell(), state, req).deep_out, "asked.exr");
}

TEST(FramePlan, ASequenceIsNotGatheredAnewFrameByFrame) {
    test::expect_refused(
        "render " + test::source_dir() + "/scenes/shots/cornell-rolling.json --frames 1-2 --regather -o /tmp/never.####.exr",
        {"--regather", "--frame"});
}

}  // namespace
}  // namespace bounce
