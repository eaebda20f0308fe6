// Settings leave the scene (issue 63): plan_frame resolves each stage's settings once and every
// pass takes its own from the plan; a front end reads a setting by its name through the table.
#include <gtest/gtest.h>

#include "bounce/config/params.h"
#include "bounce/render/render.h"
#include "test_util.h"

namespace bounce {
namespace {

Scene cornell(std::vector<Override> extra = {}) {
    std::vector<Override> o = {"camera.resolution=[32,32]", "render.spp=1", "render.rays=32", "render.light_samples=2"};
    o.insert(o.end(), extra.begin(), extra.end());
    return load_scene(test::cornell_scene(), o);
}

TEST(PlanSettings, ThePlanResolvesWhatEachPassTakes) {
    const Scene s = cornell({"render.gi=\"cache\"", "render.seed=77", "render.tile_size=8", "render.tile_order=\"spiral\"",
                             "render.ray_offset=0.25", "render.light_pick=5", "render.specular_depth=3", "render.light_parts=true",
                             "render.correction_rays=4", "render.correction_prediction=\"hits\"", "render.cache_sharing=\"per-thread\""});
    const FramePlan p = plan_frame(s, {}, {});
    // Frame-wide: the seed and tiles every per-pixel pass lays its work out by.
    EXPECT_EQ(p.tiling().seed, 77u);
    EXPECT_EQ(p.tiling().tile_size, 8);
    EXPECT_EQ(p.tiling().tile_order, TileOrder::Spiral);
    EXPECT_EQ(p.gather.tiling.seed, 77u);
    EXPECT_EQ(p.shade().tiling.tile_size, 8);
    // The automatic AO distance is 10 % of the scene's size, resolved once.
    EXPECT_FLOAT_EQ(p.gather.ao_distance, 0.1f * s.size());
    // Light parts and the records' predictions only where a cache keeps them.
    EXPECT_TRUE(p.gather.light_parts);
    EXPECT_TRUE(p.gather.prediction && p.gather.prediction_hits);
    EXPECT_TRUE(p.find<RadiosityStep>()->settings.light_parts);
    EXPECT_TRUE(p.find<CacheStartStep>()->light_parts);
    // Each step carries its stage's own.
    EXPECT_FLOAT_EQ(p.find<AccelStep>()->lighting.ray_offset, 0.25f);
    EXPECT_EQ(p.find<AccelStep>()->lighting.light_pick, 5);
    EXPECT_EQ(p.find<VisibilityStep>()->settings.seed, 77u);
    EXPECT_EQ(p.find<GatherRecordsStep>()->sharing, CacheSharing::PerThread);
    EXPECT_EQ(p.shade().shading.specular_depth, 3);
    EXPECT_EQ(p.indirect(), IndirectFrom::Cache);

    // Brute force keeps no parts and predicts nothing, whatever the cache settings say.
    const FramePlan b = plan_frame(cornell({"render.gi=\"brute\"", "render.light_parts=true", "render.correction_rays=4"}), {}, {});
    EXPECT_FALSE(b.gather.light_parts);
    EXPECT_FALSE(b.gather.prediction);
    EXPECT_EQ(b.indirect(), IndirectFrom::Brute);
    // A set AO distance is the one gathers use.
    EXPECT_FLOAT_EQ(plan_frame(cornell({"render.ao=true", "render.ao_distance=3"}), {}, {}).gather.ao_distance, 3.0f);
}

TEST(PlanSettings, APassUsesThePlansSettingsNotTheScenes) {
    // The same scene run with a plan whose tiling says another seed renders another image; with
    // the scene's own plan, the image of `render`.
    const Scene s = cornell({"render.gi=\"brute\""});
    Stats a_stats, b_stats, c_stats;
    const RenderResult a = render(s, {}, a_stats, nullptr);
    FramePlan p = plan_frame(s, {}, {});
    const RenderResult same = run_frame(s, p, {}, {}, b_stats, nullptr);
    EXPECT_EQ(test::differing_values(a.image, same.image), 0u);
    p.gather.tiling.seed = 12345;  // the plan's one copy of the seed
    const RenderResult other = run_frame(s, p, {}, {}, c_stats, nullptr);
    EXPECT_GT(test::differing_values(a.image, other.image), 0u);
}

TEST(PlanSettings, AFrontEndReadsAndSetsASettingByItsName) {
    Scene s = cornell();
    EXPECT_EQ(param_value(s, "render.gi"), "none");
    set_param_value(s, "render.gi", "cache");
    set_param_value(s, "render.crop", std::array<int, 4>{1, 9, 2, 8});
    EXPECT_EQ(s.render.indirect.gi, GiMode::Cache);
    EXPECT_EQ(param_value(s, "render.crop"), nlohmann::json::array({1, 9, 2, 8}));
    EXPECT_EQ(param_value(s, "camera.resolution"), nlohmann::json::array({32, 32}));
    // Checked as a scene file's value is, with the table's message; unknown keys are refused.
    try {
        set_param_value(s, "render.rays", -1);
        FAIL() << "a negative ray count was taken";
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("out of range"), std::string::npos) << e.what();
    }
    EXPECT_THROW(set_param_value(s, "render.gi", "sometimes"), std::invalid_argument);
    EXPECT_THROW(set_param_value(s, "render.rays", std::nan("")), std::invalid_argument);
    EXPECT_THROW(param_value(s, "render.no_such_thing"), std::out_of_range);
    EXPECT_EQ(s.render.indirect.rays, 32);  // untouched by the refused values
}

}  // namespace
}  // namespace bounce
