// Thin translucent surfaces (issue 61, item 3): diffuse transmission lets the light arriving at
// one side of a leaf leave by the other, for direct light (an analytic thin slab under a
// distant light), for bounce light (a card over a lit floor, whose back side's records the
// cache interpolates, against the analytic value and brute force), read from glTF's
// KHR_materials_diffuse_transmission as from the scene file, and refused out of range.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "material_scenes.h"
#include "test_util.h"

namespace bounce {
namespace {

using nlohmann::json;
using namespace test_scenes;

constexpr double kInvPiD = 1 / std::numbers::pi;
const json kRho = {0.2, 0.6, 0.1}, kRhoT = {0.9, 0.8, 0.3};
constexpr double kT = 0.4, kSun = 3;

json leaf_material(double t) { return {{"color", kRho}, {"diffuse_transmission", t}, {"diffuse_transmission_color", kRhoT}}; }

/// A large horizontal card at y = 0 seen from above, under a distant light of irradiance kSun
/// (perpendicular) travelling along `direction`.
json slab(const json& direction) {
    return {{"camera", {{"position", {0, 3, -2}}, {"look_at", {0, 0, 0}}, {"fov", 30}, {"resolution", {16, 12}}}},
            {"render", {{"spp", 1}, {"light_samples", 1}, {"seed", 3}}},
            {"materials", {{"leaf", leaf_material(kT)}}},
            {"lights", {{{"type", "distant"}, {"direction", direction}, {"intensity", kSun}}}},
            {"objects",
             {{{"name", "card"},
               {"type", "quad"},
               {"material", "leaf"},
               {"vertices", {{-50, 0, -50}, {-50, 0, 50}, {50, 0, 50}, {50, 0, -50}}}}}}};
}

/// Every pixel's `layer` against `expected` (per channel), within `rel` of it.
void expect_everywhere(const Image& img, const char* layer, const Color& expected, double rel) {
    const Layer* l = img.find(layer);
    ASSERT_NE(l, nullptr) << layer;
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x)
            for (int c = 0; c < 3; ++c)
                ASSERT_NEAR(img.at(*l, x, y)[c], expected[c], rel * std::abs(expected[c]) + 1e-7) << layer << " at " << x << "," << y;
}

Color color_of(const json& j, double scale) {
    return Color(static_cast<float>(j[0].get<double>() * scale), static_cast<float>(j[1].get<double>() * scale),
                 static_cast<float>(j[2].get<double>() * scale));
}

// Lit from behind at cosine 0.8, the top shows t rho_t E / pi; lit from the front, (1 - t) rho E / pi.
TEST(Translucency, ABackLitCardIsTheThinSlabsAnalyticValue) {
    const double e = kSun * 0.8;
    expect_everywhere(render_with(slab({0.6, 0.8, 0}), "none"), "direct", color_of(kRhoT, kT * e * kInvPiD), 1e-5);
    expect_everywhere(render_with(slab({0.6, -0.8, 0}), "none"), "direct", color_of(kRho, (1 - kT) * e * kInvPiD), 1e-5);
    // Opaque, the card's top is black from behind.
    json opaque = slab({0.6, 0.8, 0});
    opaque["materials"]["leaf"].erase("diffuse_transmission");
    expect_everywhere(render_with(opaque, "none"), "direct", Color(0), 0);
}

/// A translucent card of half-size 0.5 at height 1 over a floor (albedo 0.5) that reaches nearly
/// to the horizon, under a sun at cosine 0.8 whose shadows the card does not cast: the floor
/// is uniformly lit, so the card's back hemisphere takes E_back = 0.5 x 0.8 kSun and its front none.
json card_over_floor(double t) {
    json j = {
        {"camera", {{"position", {0, 1.9, -0.6}}, {"look_at", {0, 1, 0}}, {"fov", 25}, {"resolution", {16, 12}}}},
        {"render", {{"spp", 1}, {"light_samples", 1}, {"seed", 5}, {"rays", 64}}},
        {"materials", {{"leaf", leaf_material(t)}, {"ground", {{"color", 0.5}}}}},
        {"lights", {{{"type", "distant"}, {"direction", {0.6, -0.8, 0}}, {"intensity", kSun}, {"shadow_link", {{"exclude", {"card"}}}}}}},
        {"objects",
         {{{"name", "floor"},
           {"type", "quad"},
           {"material", "ground"},
           {"vertices", {{-3000, 0, -3000}, {-3000, 0, 3000}, {3000, 0, 3000}, {3000, 0, -3000}}}},
          {{"name", "card"},
           {"type", "quad"},
           {"material", "leaf"},
           {"vertices", {{-0.5, 1, -0.5}, {-0.5, 1, 0.5}, {0.5, 1, 0.5}, {0.5, 1, -0.5}}}}}}};
    return j;
}

// The bounce light of the floor reaches the camera through the card: the indirect layer is
// t E_back (the front takes none), the beauty adds rho_t t E_back / pi, in brute force and
// through the cache, whose back side's records serve every fragment.
TEST(Translucency, BounceLightThroughACardIsItsBackSidesIrradiance) {
    const double e_back = 0.5 * 0.8 * kSun;
    const Color beauty = color_of(kRho, (1 - kT) * 0.8 * kSun * kInvPiD) + color_of(kRhoT, kT * e_back * kInvPiD);
    for (const char* gi : {"brute", "cache"}) {
        SCOPED_TRACE(gi);
        Stats stats;
        const RenderResult r =
            render(test::scene_from(card_over_floor(kT), {Override(std::string("render.gi=") + gi)}), {}, stats, nullptr);
        expect_everywhere(r.image, "indirect", Color(static_cast<float>(kT * e_back)), 2e-3);
        expect_everywhere(r.image, "beauty", beauty, 2e-3);
        if (std::string(gi) == "cache") {
            EXPECT_EQ(r.shading_misses, 0u);
            size_t back = 0;
            for (size_t i = 0; i < r.cache->size(); ++i) back += r.cache->record(i).n.y < -0.99f;
            EXPECT_GT(back, 0u);               // the card's back side has records of its own
            EXPECT_LT(back, r.cache->size());  // and its front too
        }
    }
    // Opaque, nothing comes through: the card's front sees nothing to bounce light.
    expect_everywhere(render_with(card_over_floor(0), "cache"), "indirect", Color(0), 0);
}

TEST(Translucency, GltfsDiffuseTransmissionIsTheSceneFiles) {
    test::TempDir dir;
    write_png(dir.file("leaf.png"), 1, 1, 3, {255, 255, 255});
    const json m = {
        {"pbrMetallicRoughness", {{"baseColorFactor", {0.2, 0.6, 0.1, 1}}, {"metallicFactor", 0}, {"roughnessFactor", 1}}},
        {"doubleSided", true},
        {"extensions",
         {{"KHR_materials_diffuse_transmission", {{"diffuseTransmissionFactor", kT}, {"diffuseTransmissionColorFactor", kRhoT}}}}}};
    json same = leaf_material(kT);
    same["specular"] = 0.04, same["roughness"] = 1;
    json card = {{"name", "card"}, {"type", "mesh"}, {"file", gltf_card(dir, m)}};
    // Lit from both sides: the stage's light in front of the card and a second one behind it.
    json a = stage(json::array({card}), kLeaf), b = stage(json::array({quad("card", "leaf", -1, 1, 0.2, 2.2, 0)}), same);
    for (json* s : {&a, &b})
        (*s)["lights"].push_back(
            {{"type", "quad"}, {"corner", {-0.2, 1, 1.5}}, {"edge_u", {0, 0.4, 0}}, {"edge_v", {0.4, 0, 0}}, {"color", 100}});
    const Image ga = render_with(a, "brute"), gb = render_with(b, "brute");
    EXPECT_EQ(test::differing_values(ga, gb), 0u);
    json opaque = same;
    opaque.erase("diffuse_transmission");
    b["materials"]["leaf"] = opaque;
    EXPECT_GT(test::differing_values(ga, render_with(b, "brute")), 100u);  // the transmission shows
}

TEST(Translucency, OutOfRangeValuesAreRefusedNamingThePlace) {
    for (const json& bad : {json(NAN), json(2), json(-0.1), json("half")}) {
        json s = slab({0, -1, 0});
        s["materials"]["leaf"]["diffuse_transmission"] = bad;
        test::expect_input_error([&] { test::scene_from(s); }, {"/materials/leaf/diffuse_transmission"});
    }
    json s = slab({0, -1, 0});
    s["materials"]["leaf"]["diffuse_transmission_color"] = {1.5, 0, 0};
    test::expect_input_error([&] { test::scene_from(s); }, {"/materials/leaf/diffuse_transmission_color"});
    s = slab({0, -1, 0});
    s["materials"]["leaf"]["transmission"] = 0.5;
    test::expect_input_error([&] { test::scene_from(s); }, {"/materials/leaf/diffuse_transmission", "not both"});
    // glTF: a factor of 2, a colour of two numbers.
    test::TempDir dir;
    write_png(dir.file("leaf.png"), 1, 1, 3, {255, 255, 255});
    for (const json& ext : {json{{"diffuseTransmissionFactor", 2}}, json{{"diffuseTransmissionColorFactor", {1, 1}}}}) {
        const json m = {{"extensions", {{"KHR_materials_diffuse_transmission", ext}}}};
        const std::string file = gltf_card(dir, m);
        const json g = stage(json::array({{{"name", "card"}, {"type", "mesh"}, {"file", file}}}), kLeaf);
        test::expect_input_error([&] { test::scene_from(g); }, {"card.gltf", "/materials/0/extensions/KHR_materials_diffuse_transmission"});
    }
}

}  // namespace
}  // namespace bounce
