// Fur's visible_to: the same four flags as an object's (camera, shadows, gathers, mirrors),
// with cast_shadows / cast_indirect as the older names of two of them.
#include <gtest/gtest.h>

#include "bounce/core/error.h"
#include "bounce/render/render.h"
#include "test_util.h"

namespace bounce {
namespace {

using nlohmann::json;

/// A unit lawn of short strands under a low sun, seen from above at an angle; `mirror` adds an
/// upright mirror behind it that the camera sees the lawn in.
json lawn(const json& fur_extra, bool mirror = false) {
    json fur = {{"count", 3000}, {"length", 0.1}, {"width_root", 0.004}, {"width_tip", 0.002}, {"lean", 0.2}};
    fur.update(fur_extra);
    json j = test::base_scene();
    j["camera"] = {{"position", {0, 0.8, 1.2}}, {"look_at", {0, 0.1, 0}}, {"fov", 50}, {"resolution", {48, 36}}};
    j["render"] = {{"spp", 1}, {"light_samples", 1}, {"layers", "components"}};
    j["materials"] = {{"mirror", {{"color", 0.5}, {"mirror", 1}}}};
    j["objects"] = json::array({{{"name", "lawn"},
                                 {"type", "quad"},
                                 {"vertices", {{-0.5, 0, -0.5}, {-0.5, 0, 0.5}, {0.5, 0, 0.5}, {0.5, 0, -0.5}}},
                                 {"fur", fur}}});
    if (mirror)
        j["objects"].push_back({{"name", "mirror"},
                                {"type", "quad"},
                                {"material", "mirror"},
                                {"vertices", {{-0.6, 0, -0.5}, {0.6, 0, -0.5}, {0.6, 0.8, -0.5}, {-0.6, 0.8, -0.5}}}});
    j["lights"] = json::array({{{"type", "distant"}, {"direction", {1, -0.5, 0}}, {"color", 1}}});
    return j;
}

RenderResult render_lawn(const json& j) {
    Stats stats;
    return render(test::scene_from(j), {}, stats, nullptr);
}

/// Mean direct light on the ground's pixels (one fragment, not hair).
double ground_direct(const RenderResult& r) {
    const Layer& d = *r.image.find("direct");
    double sum = 0;
    size_t n = 0;
    for (int y = 0; y < r.deep.height; ++y)
        for (int x = 0; x < r.deep.width; ++x) {
            auto frags = r.deep.pixel(x, y);
            if (frags.size() != 1 || frags[0].is_hair() || frags[0].object != 0) continue;
            sum += d.data[3 * (static_cast<size_t>(y) * r.deep.width + x)], ++n;
        }
    return n ? sum / static_cast<double>(n) : NAN;
}

size_t hair_fragments(const RenderResult& r) {
    return static_cast<size_t>(
        std::count_if(r.deep.fragments.begin(), r.deep.fragments.end(), [](const Fragment& f) { return f.is_hair(); }));
}

TEST(FurVisibility, VisibleToShadowsIsCastShadows) {
    const RenderResult old_name = render_lawn(lawn({{"cast_shadows", false}}));
    const RenderResult flag = render_lawn(lawn({{"visible_to", {{"shadows", false}}}}));
    EXPECT_EQ(old_name.image.find("beauty")->data, flag.image.find("beauty")->data);
    const RenderResult shadowed = render_lawn(lawn(json::object()));
    // Unshadowed ground: albedo 0.7 x E / pi with E = cos = 0.5 / |(1, -0.5, 0)|.
    EXPECT_NEAR(ground_direct(flag), 0.7 / kPi * 0.5 / std::sqrt(1.25), 1e-4);
    EXPECT_LT(ground_direct(shadowed), 0.9 * ground_direct(flag));
}

TEST(FurVisibility, HiddenFromTheCameraTheStrandsStillCastShadows) {
    const RenderResult seen = render_lawn(lawn(json::object()));
    const RenderResult hidden = render_lawn(lawn({{"visible_to", {{"camera", false}}}}));
    EXPECT_GT(hair_fragments(seen), 100u);
    EXPECT_EQ(hair_fragments(hidden), 0u);
    EXPECT_LT(ground_direct(hidden), 0.9 * 0.7 / kPi * 0.5 / std::sqrt(1.25));
}

TEST(FurVisibility, IndirectInTheGatherBvhStillHonoursShadows) {
    // Seen by gathers but casting no shadows: the ground's direct light is the open value.
    const RenderResult r = render_lawn(lawn({{"visible_to", {{"indirect", true}, {"shadows", false}}}}));
    EXPECT_NEAR(ground_direct(r), 0.7 / kPi * 0.5 / std::sqrt(1.25), 1e-4);
    EXPECT_LT(ground_direct(render_lawn(lawn({{"cast_indirect", true}}))), 0.9 * ground_direct(r));
}

TEST(FurVisibility, MirrorsSeeLitStrandsWhenAsked) {
    auto mirror_light = [](bool reflections) {
        const RenderResult r = render_lawn(lawn({{"visible_to", {{"reflections", reflections}}}}, true));
        const Layer* found = r.image.find("reflection");
        EXPECT_TRUE(found);
        if (!found) return 0.0;
        const Layer& refl = *found;
        double sum = 0;
        for (float v : refl.data) sum += v;
        return sum;
    };
    const double without = mirror_light(false), with = mirror_light(true);
    EXPECT_GT(without, 0.0);
    // Strands in the mirror: lit (not black), and they change what it shows.
    EXPECT_NE(with, without);
    EXPECT_GT(with, 0.5 * without);
}

TEST(FurVisibility, OneNamePerFlag) {
    test::expect_input_error(
        [] {
            test::scene_from(lawn({{"cast_shadows", true}, {"visible_to", {{"shadows", false}}}}));
        },
        {"inline.json", "/objects/0/fur/cast_shadows", "older name of visible_to.shadows"});
    test::expect_input_error(
        [] {
            test::scene_from(lawn({{"visible_to", {{"shadow", false}}}}));
        },
        {"inline.json", "/objects/0/fur/visible_to", "shadow"});
    test::expect_input_error(
        [] {
            test::scene_from(lawn({{"visible_to", {{"camera", 2}}}}));
        },
        {"inline.json", "/objects/0/fur/visible_to/camera"});
}

}  // namespace
}  // namespace bounce
