// Records that keep their bounce light per light (render.light_parts): a light's colour or
// intensity edit re-shaded from the old records equals a full re-gather at the new values,
// bit for bit, and placement does not depend on any light's colour or intensity.
#include <gtest/gtest.h>

#include <cstring>

#include "bounce/cache/irradiance_cache.h"
#include "bounce/core/image.h"
#include "bounce/lighting/lighting.h"
#include "bounce/radiosity/radiosity.h"
#include "bounce/render/render.h"
#include "test_util.h"

namespace bounce {
namespace {

using nlohmann::json;

/// A floor, a red card standing on it and a white card above it, under a coloured sun, a sky
/// and a quad light: three light types, colour bleeding between them.
json three_light_scene(bool parts, int res = 24) {
    json j = test::base_scene();
    j["camera"] = {{"position", {0, 4, 6}}, {"look_at", {0, 0.5, 0}}, {"fov", 50}, {"resolution", {res, res}}};
    j["render"]["rays"] = 64;
    j["render"]["gi"] = "cache";
    j["render"]["light_parts"] = parts;
    j["materials"] = {{"floor", {{"color", 0.7}}}, {"red", {{"color", {0.8, 0.1, 0.1}}}}, {"white", {{"color", 0.8}}}};
    j["objects"][0]["name"] = "floor";
    j["objects"][0]["material"] = "floor";
    j["objects"].push_back({{"name", "red"},
                            {"type", "quad"},
                            {"material", "red"},
                            {"vertices", {{-0.5, 0, -0.2}, {-0.5, 1.2, -0.2}, {0.5, 1.2, -0.2}, {0.5, 0, -0.2}}}});
    j["objects"].push_back({{"name", "white"},
                            {"type", "quad"},
                            {"material", "white"},
                            {"vertices", {{-1, 1.5, -1}, {-1, 1.5, 1}, {1, 1.5, 1}, {1, 1.5, -1}}}});
    j["lights"] =
        json::array({{{"type", "distant"}, {"direction", {0.3, -1, 0.2}}, {"color", {2, 1.8, 1.5}}},
                     {{"type", "sky"}, {"color", {0.2, 0.3, 0.5}}},
                     {{"type", "quad"}, {"corner", {-0.3, 1.2, 0.5}}, {"edge_u", {0.6, 0, 0}}, {"edge_v", {0, 0, 0.4}}, {"color", 4}}});
    return j;
}

json edited(json j) {
    j["lights"][0]["color"] = {0.5, 2.5, 1};
    j["lights"][1]["intensity"] = 3;
    j["lights"][2]["color"] = {0, 1, 6};  // a channel at 0 and back again is still exact
    return j;
}

RenderResult fresh(const json& j) {
    Stats stats;
    return render(test::scene_from(j), {}, stats, nullptr);
}

/// A re-shade of `scene` from the state `state` left: the records as they are, no new deep buffer.
RenderResult reshade(const Scene& scene, const FrameState& state) {
    RenderRequest req;
    req.kind = FrameKind::Reshade;
    req.force = true;
    req.cache_reuse = CacheReuse::Any;
    Stats stats;
    return run_frame(scene, plan_frame(scene, state, req), state, req, stats, nullptr);
}

bool same_bits(const Image& a, const Image& b, const std::string& layer) {
    const Layer *la = a.find(layer), *lb = b.find(layer);
    if (!la || !lb || a.width != b.width || a.height != b.height) return false;
    for (int y = 0; y < a.height; ++y)
        for (int x = 0; x < a.width; ++x)
            if (std::memcmp(&a.at(*la, x, y)[0], &b.at(*lb, x, y)[0], 3 * sizeof(float)) != 0) return false;
    return true;
}

TEST(LightParts, AColourAndIntensityEditRescalesTheBounceLightExactly) {
    RenderResult before = fresh(three_light_scene(true));
    ASSERT_TRUE(before.cache);
    ASSERT_GT(before.cache->size(), 5u);
    EXPECT_TRUE(before.cache->has_light_parts(3));
    const FrameState state = before.release_state();
    const Scene after = test::scene_from(edited(three_light_scene(true)));
    const RenderResult rescaled = reshade(after, state);
    const RenderResult regathered = fresh(edited(three_light_scene(true)));
    EXPECT_EQ(rescaled.records_new, 0u);
    EXPECT_EQ(rescaled.shading_misses, 0u);
    // The same records, at the same places, with the same values, bit for bit.
    ASSERT_EQ(rescaled.cache->size(), regathered.cache->size());
    for (size_t i = 0; i < regathered.cache->size(); ++i) {
        const Record &a = rescaled.cache->record(i), &b = regathered.cache->record(i);
        ASSERT_EQ(std::memcmp(&a.p, &b.p, sizeof(Vec3)), 0) << i;
        ASSERT_EQ(std::memcmp(&a.E, &b.E, sizeof(Color)), 0) << i;
        ASSERT_EQ(std::memcmp(a.grad_t.data(), b.grad_t.data(), sizeof(a.grad_t)), 0) << i;
        ASSERT_EQ(std::memcmp(a.dir.data(), b.dir.data(), sizeof(a.dir)), 0) << i;
        ASSERT_EQ(a.radius, b.radius) << i;
    }
    EXPECT_TRUE(same_bits(rescaled.image, regathered.image, "indirect"));
    EXPECT_TRUE(same_bits(rescaled.image, regathered.image, "beauty"));
    // The edit changed the bounce light: the old records' light is not the new one.
    EXPECT_FALSE(same_bits(fresh(three_light_scene(true)).image, regathered.image, "indirect"));
}

TEST(LightParts, WithoutPartsTheReshadeKeepsTheOldBounceLight) {
    RenderResult before = fresh(three_light_scene(false));
    EXPECT_FALSE(before.cache->has_light_parts(3));
    const FrameState state = before.release_state();
    const RenderResult reshaded = reshade(test::scene_from(edited(three_light_scene(false))), state);
    EXPECT_FALSE(same_bits(reshaded.image, fresh(edited(three_light_scene(false))).image, "indirect"));
}

TEST(LightParts, RecordsSumTheirPartsAtTheLightScales) {
    const Scene s = test::scene_from(three_light_scene(true));
    Stats stats;
    const RenderResult r = render(s, {}, stats, nullptr);
    const std::vector<Color> scales = light_scales(s);
    ASSERT_EQ(scales.size(), 3u);
    EXPECT_EQ(scales[1], Color(0.2f, 0.3f, 0.5f));
    size_t lit_by_all = 0;
    for (size_t i = 0; i < r.cache->size(); ++i) {
        const Record& rec = r.cache->record(i);
        ASSERT_TRUE(rec.parts);
        const LightPart sum = combine_parts(*rec.parts, scales);
        EXPECT_EQ(std::memcmp(&sum.E, &rec.E, sizeof(Color)), 0);
        // The sky's part is what a white sky of radiance 1 gives: at most pi.
        EXPECT_LE(rec.parts->light[1].E.x, kPi * 1.0001f);
        lit_by_all += rec.parts->light[0].E.x > 0 && rec.parts->light[1].E.x > 0 && rec.parts->light[2].E.x > 0;
        // The signal is every light at scale 1.
        const LightPart unit = combine_parts(*rec.parts, std::vector<Color>(3, Color(1)));
        EXPECT_NEAR(unit.E.y, rec.parts->signal.E.y, 1e-5f * std::max(1.0f, unit.E.y));
    }
    EXPECT_GT(lit_by_all, 0u);
}

TEST(LightParts, TheRadiosityBakeKeepsEachLightsUnitPart) {
    json j = three_light_scene(true);
    j["lights"] = json::array({{{"type", "distant"}, {"direction", {0, -1, 0}}, {"color", 2}}, {{"type", "sky"}, {"color", 0.5}}});
    j["objects"].erase(1), j["objects"].erase(1);  // the floor alone: no shadows
    const Scene s = test::scene_from(j);
    SceneAccel accel(s, s.render.lighting);
    Materials materials(s);
    DirectLighting lighting(s, accel, s.render.lighting);
    Stats stats;
    RadiositySettings with_parts;
    with_parts.light_parts = true;  // as the plan hands it over with render.light_parts
    EXPECT_EQ(test::still_plan(s).find<RadiosityStep>()->settings.light_parts, true);
    const RadiosityTextures rt = RadiosityTextures::bake(s, materials, lighting, with_parts, stats, nullptr);
    ASSERT_TRUE(rt.has_parts());
    Color parts[2];
    Counters c;
    rt.lookup_parts(0, 0, 0.3f, 0.3f, true, c, parts);
    // Albedo 0.7 / pi times: the sun's unit irradiance (1, straight down) and a white sky's (pi).
    EXPECT_NEAR(parts[0].x, 0.7f * kInvPi, 1e-6f);
    EXPECT_NEAR(parts[1].x, 0.7f, 1e-5f);
    EXPECT_NEAR(rt.lookup(0, 0, 0.3f, 0.3f, true, c).x, 0.7f * kInvPi * 2 + 0.7f * 0.5f, 1e-5f);
}

TEST(LightParts, PlacementDependsOnNoLightsIntensity) {
    json dim = three_light_scene(true, 48);
    dim["lights"][0]["intensity"] = 0.01;
    const RenderResult a = fresh(three_light_scene(true, 48)), b = fresh(dim);
    ASSERT_EQ(a.cache->size(), b.cache->size());
    for (size_t i = 0; i < a.cache->size(); ++i) {
        EXPECT_EQ(std::memcmp(&a.cache->record(i).p, &b.cache->record(i).p, sizeof(Vec3)), 0);
        EXPECT_EQ(a.cache->record(i).rays, b.cache->record(i).rays);
        EXPECT_EQ(a.cache->record(i).weber, b.cache->record(i).weber);  // the reach
        EXPECT_EQ(a.cache->record(i).radius, b.cache->record(i).radius);
    }
    // Without parts the records' reach follows the lights' balance (the Weber limit).
    json dim_plain = three_light_scene(false, 48);
    dim_plain["lights"][0]["intensity"] = 0.01;
    const RenderResult c = fresh(three_light_scene(false, 48)), d = fresh(dim_plain);
    bool differ = c.cache->size() != d.cache->size() || c.cache->fragment_record_count() != d.cache->fragment_record_count();
    for (size_t i = 0; !differ && i < c.cache->size(); ++i) differ = c.cache->record(i).weber != d.cache->record(i).weber;
    EXPECT_TRUE(differ);
}

}  // namespace
}  // namespace bounce
