// The lighter's per-object controls on tiny scenes with exact values: light linking and shadow
// linking (direct light, the radiosity bake), visibility to camera / shadows / gathers, and
// holdout mattes.
#include <gtest/gtest.h>

#include "bounce/core/image.h"
#include "bounce/lighting/lighting.h"
#include "bounce/radiosity/radiosity.h"
#include "bounce/render/render.h"
#include "test_util.h"

namespace bounce {
namespace {

using nlohmann::json;

constexpr float kSun = 2;  // irradiance of the distant light straight down

/// The floor (albedo 0.7) and a card (albedo 0.3) one unit above its middle, under a sun.
json card_scene(const json& light_extra = json::object(), const json& card_extra = json::object()) {
    json j = test::base_scene();
    j["materials"] = {{"floor", {{"color", 0.7}}}, {"card", {{"color", 0.3}}}};
    j["objects"][0]["name"] = "floor";
    j["objects"][0]["material"] = "floor";
    json card = {{"name", "card"}, {"type", "quad"}, {"material", "card"}, {"vertices", {{-1, 1, -1}, {-1, 1, 1}, {1, 1, 1}, {1, 1, -1}}}};
    if (!card_extra.is_null()) card.update(card_extra);
    j["objects"].push_back(card);
    json sun = {{"type", "distant"}, {"direction", {0, -1, 0}}, {"color", kSun}};
    if (!light_extra.is_null()) sun.update(light_extra);
    j["lights"] = json::array({sun});
    return j;
}

/// Irradiance at `p` (facing up) on object `object`.
float sun_at(const Scene& s, const Vec3& p, uint32_t object) {
    SceneAccel accel(s, s.render.lighting);
    DirectLighting lighting(s, accel, s.render.lighting);
    Counters c;
    return lighting.irradiance(p, {0, 1, 0}, object, RandomStream(1, 1), 1, c).x;
}

Image render_image(const Scene& s) {
    Stats stats;
    return render(s, {}, stats, nullptr).image;
}

float pixel(const Image& img, const std::string& layer, int x, int y, int channel = 0) {
    const Layer* l = img.find(layer);
    EXPECT_TRUE(l) << layer;
    return l ? img.at(*l, x, y)[channel] : NAN;
}

// Pixel (8, 8) sees the card (or, where it is hidden, the floor under it); (1, 1) the open floor.
constexpr int kMid = 8, kOpen = 1;

TEST(LightLinking, AnUnlinkedObjectGetsNoDirectLightFromTheLightAndTheOthersAllOfIt) {
    const float lit_card = 0.3f * kSun * kInvPi, lit_floor = 0.7f * kSun * kInvPi;
    const Image all = render_image(test::scene_from(card_scene()));
    EXPECT_NEAR(pixel(all, "direct", kMid, kMid), lit_card, 1e-6f);
    EXPECT_NEAR(pixel(all, "direct", kOpen, kOpen), lit_floor, 1e-6f);
    for (const json& link : {json{{"exclude", {"card"}}}, json{{"include", {"fl*"}}}}) {
        const Image img = render_image(test::scene_from(card_scene({{"light_link", link}})));
        EXPECT_EQ(pixel(img, "direct", kMid, kMid), 0.0f) << link;
        EXPECT_NEAR(pixel(img, "direct", kOpen, kOpen), lit_floor, 1e-6f) << link;
        // The card still casts its shadow: the link is about what the light lights.
        EXPECT_EQ(sun_at(test::scene_from(card_scene({{"light_link", link}})), {0, 0, 0}, 0), 0.0f);
    }
}

TEST(LightLinking, TheRadiosityBakeUsesTheSameLinks) {
    const Scene s = test::scene_from(card_scene({{"light_link", {{"exclude", {"card"}}}}}));
    SceneAccel accel(s, s.render.lighting);
    Materials materials(s);
    DirectLighting lighting(s, accel, s.render.lighting);
    Stats stats;
    const RadiosityTextures rt = RadiosityTextures::bake(s, materials, lighting, {}, stats, nullptr);
    // The card's top (its front faces down: vertices wind clockwise seen from above) and the floor's.
    const float card_top = std::max(rt.object(1).lookup(0, 0.3f, 0.3f, true).x, rt.object(1).lookup(0, 0.3f, 0.3f, false).x);
    EXPECT_EQ(card_top, 0.0f);
    const float floor_top = std::max(rt.object(0).lookup(0, 0.1f, 0.1f, true).x, rt.object(0).lookup(0, 0.1f, 0.1f, false).x);
    EXPECT_NEAR(floor_top, 0.7f * kSun * kInvPi, 1e-6f);
}

TEST(ShadowLinking, OnlyTheLinkedObjectsCastTheLightsShadows) {
    const Vec3 under{0, 0, 0};
    EXPECT_EQ(sun_at(test::scene_from(card_scene()), under, 0), 0.0f);
    EXPECT_EQ(sun_at(test::scene_from(card_scene({{"shadow_link", {{"exclude", {"card"}}}}})), under, 0), kSun);
    EXPECT_EQ(sun_at(test::scene_from(card_scene({{"shadow_link", {{"include", {"floor"}}}}})), under, 0), kSun);
    EXPECT_EQ(sun_at(test::scene_from(card_scene({{"shadow_link", {{"include", {"card"}}}}})), under, 0), 0.0f);
    // A second, unlinked light keeps every shadow.
    json j = card_scene({{"shadow_link", {{"exclude", {"card"}}}}});
    j["lights"].push_back({{"type", "distant"}, {"direction", {0, -1, 0}}, {"color", 3}});
    EXPECT_EQ(sun_at(test::scene_from(j), under, 0), kSun);
}

TEST(ShadowLinking, ALinkThatMatchesNothingOrTooManyLinkedLightsAreRefused) {
    test::expect_input_error(
        [] {
            test::scene_from(card_scene({{"shadow_link", {{"exclude", {"crad"}}}}}));
        },
        {"inline.json", "/lights/0/shadow_link/exclude/0", "\"crad\" matches no object's name"});
    test::expect_input_error(
        [] {
            test::scene_from(card_scene({{"light_link", {{"include", "card"}}}}));
        },
        {"/lights/0/light_link/include", "expected an array"});
    test::expect_input_error(
        [] {
            test::scene_from(card_scene({{"light_link", {{"include", {"card"}}, {"exclude", {"floor"}}}}}));
        },
        {"/lights/0/light_link", "expected {\"include\""});
    json j = card_scene();
    for (int i = 0; i <= kMaxShadowLinkedLights; ++i)
        j["lights"].push_back({{"type", "distant"}, {"direction", {0, -1, 0}}, {"shadow_link", {{"exclude", {"card"}}}}});
    test::expect_input_error([&] { test::scene_from(j); }, {"shadow_link", "at most 28 lights"});
}

TEST(Visibility, AnObjectHiddenFromShadowsLetsEveryLightThrough) {
    EXPECT_EQ(sun_at(test::scene_from(card_scene({}, {{"visible_to", {{"shadows", false}}}})), {0, 0, 0}, 0), kSun);
}

TEST(Visibility, AnObjectHiddenFromTheCameraStillCastsItsShadow) {
    const Image img = render_image(test::scene_from(card_scene({}, {{"visible_to", {{"camera", false}}}})));
    EXPECT_NEAR(pixel(img, "albedo", kMid, kMid), 0.7f, 1e-6f);  // the floor, not the card
    EXPECT_EQ(pixel(img, "direct", kMid, kMid), 0.0f);           // in the card's shadow
    // Hidden from everything, it is as if it were not there, bit for bit.
    const json none = {{"visible_to", {{"camera", false}, {"shadows", false}, {"indirect", false}}}};
    json without = card_scene();
    without["objects"].erase(1);
    const Image a = render_image(test::scene_from(card_scene({}, none))), b = render_image(test::scene_from(without));
    for (const char* layer : {"beauty", "direct", "albedo", "depth"}) {
        const Layer *la = a.find(layer), *lb = b.find(layer);
        ASSERT_TRUE(la && lb) << layer;
        EXPECT_EQ(la->data, lb->data) << layer;
    }
}

TEST(Visibility, GatherRaysPassAnObjectHiddenFromIndirectRays) {
    // Ambient occlusion under the card (hidden from the camera so the floor shows): the card
    // occludes the gathers unless it is hidden from them; nothing else is above the floor.
    const json ao = {{"gi", "brute"}, {"ao", true}, {"rays", 64}, {"ao_distance", 10}};
    auto ao_mid = [&](bool seen_by_gathers) {
        json j = card_scene({}, {{"visible_to", {{"camera", false}, {"indirect", seen_by_gathers}}}});
        j["render"] = ao;
        return pixel(render_image(test::scene_from(j)), "ao", kMid, kMid);
    };
    EXPECT_LT(ao_mid(true), 0.9f);
    EXPECT_EQ(ao_mid(false), 1.0f);
}

TEST(Matte, AHoldoutIsBlackWithAlphaZeroAndHidesWhatIsBehindIt) {
    json j = card_scene({}, {{"matte", true}});
    j["lights"].push_back({{"type", "sky"}, {"color", 0.5}});
    const Image img = render_image(test::scene_from(j));
    for (int c = 0; c < 4; ++c) EXPECT_EQ(pixel(img, "beauty", kMid, kMid, c), 0.0f) << c;
    EXPECT_EQ(pixel(img, "direct", kMid, kMid), 0.0f);
    EXPECT_EQ(pixel(img, "beauty", kOpen, kOpen, 3), 1.0f);
    EXPECT_GT(pixel(img, "beauty", kOpen, kOpen), 0.0f);
    // It still casts its shadow: a matte is an object in the scene.
    EXPECT_EQ(sun_at(test::scene_from(card_scene({}, {{"matte", true}})), {0, 0, 0}, 0), 0.0f);
}

TEST(Matte, AHoldoutGetsNoRecords) {
    // Only the card in view: as a holdout nothing it shows needs bounce light.
    json j = card_scene({}, {{"matte", true}});
    j["objects"].erase(j["objects"].begin());  // the floor
    j["render"] = {{"gi", "cache"}, {"rays", 16}};
    Stats stats;
    render(test::scene_from(j), {}, stats, nullptr);
    const json st = stats.to_json();
    EXPECT_EQ(st["records"].get<double>(), 0);
    EXPECT_EQ(st["shading_misses"].get<double>(), 0);
    j["objects"][0]["matte"] = false;
    Stats shown;
    render(test::scene_from(j), {}, shown, nullptr);
    EXPECT_GT(shown.to_json()["records"].get<double>(), 0);
}

}  // namespace
}  // namespace bounce
