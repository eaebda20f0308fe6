// Many lights: picking some of them (render.light_pick) stays unbiased, and as many lights as
// the pick are all taken, bit for bit.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "bounce/accel/accel.h"
#include "bounce/lighting/lighting.h"
#include "test_util.h"

namespace bounce {
namespace {

using nlohmann::json;

TEST(ManyLights, PickingSomeOfThemStaysUnbiasedAndFewerAreAllTaken) {
    // 400 point lights of random power over a floor: at a point, the mean of the picked estimate
    // over many seeds is the sum over every light (within 4 standard errors), and with as many
    // lights as render.light_pick every one is taken, bit for bit what light_pick 0 gives.
    json j = test::base_scene();
    json lights = json::array();
    for (int i = 0; i < 400; ++i)
        lights.push_back(
            {{"type", "point"}, {"position", {std::sin(i * 1.7) * 6, 1 + (i % 7), std::cos(i * 2.3) * 6}}, {"color", 0.5 + (i * 37 % 11)}});
    j["lights"] = lights;
    const Scene all = test::scene_from(j, {"render.light_pick=0"});
    const Scene picked = test::scene_from(j, {"render.light_pick=16"});
    SceneAccel accel(all, all.render.lighting);
    const DirectLighting full(all, accel, all.render.lighting), some(picked, accel, picked.render.lighting);
    Counters counters;
    for (const Vec3 p : {Vec3{0, 0, 0}, Vec3{3, 0, -2}, Vec3{-5, 0, 4}}) {
        const double truth = luminance(full.irradiance(p, {0, 1, 0}, 0, RandomStream(1, 2), 1, counters));
        double sum = 0, sq = 0;
        const int seeds = 4000;
        for (int s = 0; s < seeds; ++s) {
            const double v = luminance(some.irradiance(p, {0, 1, 0}, 0, RandomStream(7, static_cast<uint64_t>(s)), 1, counters));
            sum += v, sq += v * v;
        }
        const double mean = sum / seeds, sd = std::sqrt(std::max(0.0, sq / seeds - mean * mean));
        EXPECT_NEAR(mean, truth, 4 * sd / std::sqrt(seeds)) << p.x;
        EXPECT_GT(sd, 0);  // it did pick
    }
    const Scene as_many = test::scene_from(j, {"render.light_pick=400"});
    const DirectLighting every(as_many, accel, as_many.render.lighting);
    const Color a = every.irradiance({1, 0, 1}, {0, 1, 0}, 0, RandomStream(3, 4), 1, counters);
    const Color b = full.irradiance({1, 0, 1}, {0, 1, 0}, 0, RandomStream(3, 4), 1, counters);
    EXPECT_EQ(std::memcmp(&a, &b, sizeof(Color)), 0);
}

}  // namespace
}  // namespace bounce
