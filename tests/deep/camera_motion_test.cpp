// Issue 26: motion blur and depth of field in primary visibility, against analytic cases: a
// moving edge's coverage, a defocused point's disc. Shading stays at the frame's time.
#include <gtest/gtest.h>

#include <cmath>

#include "bounce/render/render.h"
#include "gltf_strip.h"
#include "test_util.h"

namespace bounce {
namespace {

using nlohmann::json;

/// Coverage of `scene` rendered without indirect light: the beauty's alpha, or with `albedo`
/// the albedo's red (objects of albedo 1 in front of a black backdrop).
std::vector<float> coverage(const Scene& scene, bool albedo = false) {
    Stats stats;
    const RenderResult r = render(scene, {}, stats, nullptr);
    const Layer& l = *r.image.find(albedo ? "albedo" : "beauty");
    std::vector<float> a;
    const size_t nc = l.channels.size();
    for (size_t i = albedo ? 0 : 3; i < l.data.size(); i += nc) a.push_back(l.data[i]);
    return a;
}

TEST(MotionBlur, AMovingEdgeCoversEachPixelForTheShareOfTheShutterItSpendsThere) {
    // 90 degrees of view from z = 10 onto z = 0: 32 x 8 pixels of 2.5 x 2.5 world units. The
    // quad's right edge moves from x = 0 to x = 10 over the shutter [0, 1] of frame 1.
    json j = test::base_scene();
    j["animation"] = {{"fps", 24}, {"frames", {1, 2}}};
    j["camera"] = {{"position", {0, 0, 10}}, {"look_at", {0, 0, 0}}, {"fov", 90}, {"resolution", {32, 8}}, {"shutter", {0, 1}}};
    j["render"] = {{"spp", 256}, {"light_samples", 1}};
    j["objects"] = {{{"type", "quad"},
                     {"vertices", {{-100, -50, 0}, {0, -50, 0}, {0, 50, 0}, {-100, 50, 0}}},
                     {"transform", {{"translate", {{"keys", {{1, {0, 0, 0}}, {2, {10, 0, 0}}}}}}}}}};
    j["lights"] = {{{"type", "distant"}, {"direction", {0, 0, -1}}}};
    const std::vector<float> a = coverage(test::scene_from(j));
    // Row 4; pixel px spans x in [-40 + 2.5 px, -37.5 + 2.5 px]: covered while the edge is past it.
    for (int px = 0; px < 32; ++px) {
        const double centre = -40 + 2.5 * (px + 0.5);
        const double want = std::clamp((10 - centre) / 10, 0.0, 1.0);
        EXPECT_NEAR(a[static_cast<size_t>(4 * 32 + px)], want, 0.03) << "pixel " << px;
    }
    // Without a shutter the edge is where frame 1 has it: a hard edge at x = 0.
    j["camera"]["shutter"] = {0, 0};
    const std::vector<float> still = coverage(test::scene_from(j));
    EXPECT_EQ(still[4 * 32 + 15], 1.0f);
    EXPECT_EQ(still[4 * 32 + 16], 0.0f);
}

TEST(MotionBlur, ACameraMovingInTheShutterBlursWhatItSeesByItsOwnMotion) {
    // The moving edge above, the other way round: the quad stands still with its right edge at
    // x = 0 and the camera slides from x = 0 to x = -10 over the shutter of frame 1 (position
    // and look_at keyed), so in the camera's view the edge moves from 0 to 10.
    json j = test::base_scene();
    j["animation"] = {{"fps", 24}, {"frames", {1, 2}}};
    j["camera"] = {{"position", {{"keys", {{1, {0, 0, 10}}, {2, {-10, 0, 10}}}}}},
                   {"look_at", {{"keys", {{1, {0, 0, 0}}, {2, {-10, 0, 0}}}}}},
                   {"fov", 90},
                   {"resolution", {32, 8}},
                   {"shutter", {0, 1}}};
    j["render"] = {{"spp", 256}, {"light_samples", 1}};
    j["objects"] = {{{"type", "quad"}, {"vertices", {{-100, -50, 0}, {0, -50, 0}, {0, 50, 0}, {-100, 50, 0}}}}};
    j["lights"] = {{{"type", "distant"}, {"direction", {0, 0, -1}}}};
    const Scene scene = test::scene_from(j);
    EXPECT_TRUE(scene.camera.moves_in_shutter());
    EXPECT_EQ(scene.camera.shutter_pose[1].position, Vec3(-10, 0, 10));
    const std::vector<float> a = coverage(scene);
    for (int px = 0; px < 32; ++px) {
        const double centre = -40 + 2.5 * (px + 0.5);
        const double want = std::clamp((10 - centre) / 10, 0.0, 1.0);
        EXPECT_NEAR(a[static_cast<size_t>(4 * 32 + px)], want, 0.03) << "pixel " << px;
    }
    // A pose the shutter reaches is checked as the frame's: here look_at meets position at close.
    json bad = j;
    bad["camera"]["look_at"] = {{"keys", {{1, {0, 0, 0}}, {2, {-10, 0, 10}}}}};
    test::expect_input_error([&] { test::scene_from(bad); },
                             {"inline.json", "/camera/look_at", "look_at equals position at shutter close (frame 2)"});
    // A shutter that closes before it opens is refused, also where a key makes it so.
    json reversed = j;
    reversed["camera"]["shutter"] = {0.5, -0.5};
    test::expect_input_error([&] { test::scene_from(reversed); },
                             {"inline.json", "/camera/shutter", "the shutter closes (-0.5) before it opens (0.5)"});
    reversed["camera"]["shutter"] = {{"keys", {{1, {0.25, 0}}, {2, {0, 1}}}}};
    test::expect_input_error([&] { test::scene_from(reversed); },
                             {"inline.json", "/camera/shutter", "the shutter closes (0) before it opens (0.25)"});
    // A camera keyed but still over the shutter (both keys alike) does not blur.
    j["camera"]["position"] = {{"keys", {{1, {0, 0, 10}}, {2, {0, 0, 10}}}}};
    j["camera"]["look_at"] = {0, 0, 0};
    const Scene still = test::scene_from(j);
    EXPECT_FALSE(still.camera.moves_in_shutter());
    const std::vector<float> b = coverage(still);
    EXPECT_EQ(b[4 * 32 + 15], 1.0f);
    EXPECT_EQ(b[4 * 32 + 16], 0.0f);
}

/// Whether (x, y) lies in triangle (a, b, c) of the plane z = 0.
bool inside(const Vec3& a, const Vec3& b, const Vec3& c, double x, double y) {
    const auto side = [&](const Vec3& p, const Vec3& q) { return (q.x - p.x) * (y - p.y) - (q.y - p.y) * (x - p.x); };
    const double s0 = side(a, b), s1 = side(b, c), s2 = side(c, a);
    return (s0 >= 0 && s1 >= 0 && s2 >= 0) || (s0 <= 0 && s1 <= 0 && s2 <= 0);
}

TEST(MotionBlur, ASkinThatMovesInTheShutterIsBlurredBetweenItsPosesAtOpenAndClose) {
    // The skinned strip of gltf_strip.h (z = 0): over the shutter [0, 1] of frame 1 (1 fps) its
    // tip turns 90 degrees, so (2, 0) -> (1, 1) and (2, 1) -> (0, 1). Motion blur sees its
    // vertices moving in straight lines between the two poses: each pixel is covered for the
    // share of the shutter (and of its area) that the strip, so interpolated, covers it.
    test::TempDir d;
    d.write("strip.gltf", test::skinned_strip().dump());
    json j = test::base_scene();
    j["animation"] = {{"fps", 1}, {"frames", {1, 2}}};
    const int n = 32;
    j["camera"] = {{"position", {1, 0.5, 6}}, {"look_at", {1, 0.5, 0}}, {"fov", 40}, {"resolution", {n, n}}, {"shutter", {0, 1}}};
    j["render"] = {{"spp", 1024}, {"light_samples", 1}};
    j["objects"] = {{{"type", "mesh"}, {"file", "strip.gltf"}, {"animation", "bend"}}};
    j["lights"] = {{{"type", "distant"}, {"direction", {0, 0, -1}}}};
    d.write("s.json", j.dump());
    const Scene scene = load_scene(d.file("s.json"));
    const Object& strip = scene.objects[0];
    ASSERT_EQ(strip.shutter[1].size(), strip.coarse.positions.size());
    const std::vector<float> a = coverage(scene);
    // The expected coverage, integrated over 16 times and 32 x 32 points per pixel.
    const double pixel = 2 * 6 * std::tan(20 * kPi / 180) / n;
    double worst = 0, sum = 0, want_sum = 0;
    for (int py = 0; py < n; ++py)
        for (int px = 0; px < n; ++px) {
            int hits = 0;
            for (int t = 0; t < 16; ++t) {
                const float time = (static_cast<float>(t) + 0.5f) / 16;
                std::vector<Vec3> p;
                for (size_t v = 0; v < strip.shutter[0].size(); ++v)
                    p.push_back(strip.shutter[0][v] + (strip.shutter[1][v] - strip.shutter[0][v]) * time);
                for (int s = 0; s < 1024; ++s) {
                    const double x = 1 + (px + (s % 32 + 0.5) / 32 - n / 2.0) * pixel,
                                 y = 0.5 - (py + (s / 32 + 0.5) / 32 - n / 2.0) * pixel;
                    bool in = false;
                    for (size_t f = 0; f + 2 < strip.coarse.indices.size() && !in; f += 3)
                        in = inside(p[strip.coarse.indices[f]], p[strip.coarse.indices[f + 1]], p[strip.coarse.indices[f + 2]], x, y);
                    hits += in;
                }
            }
            const double want = hits / (16.0 * 1024.0), got = a[static_cast<size_t>(py * n + px)];
            worst = std::max(worst, std::abs(got - want));
            sum += got, want_sum += want;
        }
    EXPECT_LT(worst, 0.03);
    EXPECT_NEAR(sum, want_sum, 0.01 * want_sum);
    // The strip swept part of its second cell away: less than its 2 units of area at rest.
    EXPECT_LT(want_sum * pixel * pixel, 1.9);
    // Without a shutter the strip is where frame 1 has it, its 2 units of area.
    j["camera"]["shutter"] = {0, 0};
    d.write("s.json", j.dump());
    const std::vector<float> still = coverage(load_scene(d.file("s.json")));
    double area = 0;
    for (float c : still) area += c;
    EXPECT_NEAR(area * pixel * pixel, 2.0, 0.02);
}

TEST(DepthOfField, APointOutOfFocusSpreadsOverItsCircleOfConfusion) {
    // Focused on z = 0 from z = 10; a ball of radius 0.5 at z = -10 (distance 20). With a lens
    // of diameter 4 its circle of confusion on the plane in focus is 4 x 10 / 20 = 2 units
    // across: 64 px over 20 units there, so a disc of radius 3.2 px around an image of radius 0.8.
    json j = test::base_scene();
    j["camera"] = {{"position", {0, 0, 10}}, {"look_at", {0, 0, 0}}, {"fov", 90},
                   {"resolution", {64, 64}}, {"aperture", 4},        {"focus_distance", 10}};
    j["render"] = {{"spp", 1024}, {"light_samples", 1}};
    j["materials"] = {{"white", {{"color", 1}}}, {"black", {{"color", 0}}}};
    j["objects"] = {
        {{"type", "sphere"},
         {"center", {0, 0, -10}},
         {"radius", 0.5},
         {"subdivisions", 4},
         {"fine_subdivisions", 1},
         {"material", "white"}},
        {{"type", "quad"}, {"material", "black"}, {"vertices", {{-500, -500, -90}, {500, -500, -90}, {500, 500, -90}, {-500, 500, -90}}}}};
    j["lights"] = {{{"type", "distant"}, {"direction", {0, 0, -1}}}};
    const auto moments = [](const std::vector<float>& a) {
        double sum = 0, r2 = 0;
        for (int y = 0; y < 64; ++y)
            for (int x = 0; x < 64; ++x) {
                const double w = a[static_cast<size_t>(y * 64 + x)], dx = x + 0.5 - 32, dy = y + 0.5 - 32;
                sum += w, r2 += w * (dx * dx + dy * dy);
            }
        return std::pair{sum, r2 / sum};
    };
    const auto [area, spread] = moments(coverage(test::scene_from(j), true));
    // The image's area is conserved (pi 0.8^2 pixels) and spread as the sphere's disc convolved
    // with the lens's: mean squared radius (3.2^2 + 0.8^2) / 2.
    EXPECT_NEAR(area, kPi * 0.8 * 0.8, 0.1 * kPi * 0.8 * 0.8);
    EXPECT_NEAR(std::sqrt(2 * spread), std::sqrt(3.2 * 3.2 + 0.8 * 0.8), 0.25);
    // A pinhole keeps it a disc of radius 0.8.
    j["camera"]["aperture"] = 0;
    const auto [area0, spread0] = moments(coverage(test::scene_from(j), true));
    EXPECT_NEAR(area0, kPi * 0.8 * 0.8, 0.1 * kPi * 0.8 * 0.8);
    EXPECT_LT(std::sqrt(2 * spread0), 1.2);
}

}  // namespace
}  // namespace bounce
