// Hessian records: the gather's irradiance Hessian against an analytic field, and elliptical
// weights that reach their bound at both radii.
#include <gtest/gtest.h>

#include "bounce/accel/accel.h"
#include "bounce/cache/cache_file.h"
#include "bounce/cache/record.h"
#include "bounce/render/render.h"
#include "bounce/scene/scene_load.h"
#include "bounce/gather/gather.h"
#include "bounce/lighting/lighting.h"
#include "bounce/lighting/materials.h"
#include "test_util.h"

namespace bounce {
namespace {

TEST(Hessian, EllipseWeightReachesItsBoundAtBothRadii) {
    Record r;
    r.p = {0, 0, 0};
    r.n = {0, 0, 1};
    r.radius = 1;
    r.radius_long = 3;
    r.axis = {1, 0, 0};
    CacheSettings s;
    s.metric = Metric::Hessian;
    auto w = [&](const Vec3& p) { return record_weight(r, p, {0, 0, 1}, RecordMetric(s)); };
    EXPECT_GT(w({2.97f, 0, 0}), 0.0f);
    EXPECT_EQ(w({3.03f, 0, 0}), 0.0f);
    EXPECT_GT(w({0, 0.99f, 0}), 0.0f);
    EXPECT_EQ(w({0, 1.01f, 0}), 0.0f);
    EXPECT_NEAR(w({1.5f, 0, 0}), 0.5f, 1e-5f);  // half way along the long axis
    EXPECT_NEAR(w({0, 0.5f, 0}), 0.5f, 1e-5f);  // and across it
    EXPECT_FLOAT_EQ(record_support(r, s), 3.0f);
    r.radius_long = 0;  // round again
    EXPECT_EQ(w({1.5f, 0, 0}), 0.0f);
}

/// A floor point at distance x from an infinitely long wall of height h, AO only: the
/// unoccluded cosine-weighted fraction is A(x) = 1/2 + x / (2 sqrt(x^2 + h^2)).
TEST(Hessian, AoNearAWallMatchesTheAnalyticSecondDerivative) {
    const float h = 1, big = 1e4f;
    nlohmann::json j = test::base_scene();
    j["objects"].push_back({{"type", "quad"}, {"vertices", {{0, 0, -big}, {0, h, -big}, {0, h, big}, {0, 0, big}}}});
    j["lights"] = {{{"type", "sky"}, {"color", 1.0}}};
    Scene scene = test::scene_from(j);
    SceneAccel accel(scene, scene.render.lighting);
    Materials materials(scene);
    DirectLighting lighting(scene, accel, scene.render.lighting);
    GatherSettings gs;
    gs.rays = 4096;
    gs.ao = true;
    gs.ao_distance = 0;
    gs.hessian = true;
    Gatherer g(scene, accel, materials, lighting, nullptr, gs);
    for (float x : {0.5f, 1.0f, 2.0f}) {
        Counters c;
        GatherResult r = g.gather({x, 1e-3f, 0}, {0, 1, 0}, RandomStream(5, 1), c);
        const double s2 = double(x) * x + double(h) * h;
        const double a = 0.5 + 0.5 * x / std::sqrt(s2);
        const double a2 = -1.5 * h * h * x / std::pow(s2, 2.5);
        EXPECT_NEAR(r.ao, a, 0.01) << x;
        // Measured: 0.74 / 0.32 / 0.047 against 0.59 / 0.31 / 0.057 at x = 0.5 / 1 / 2.
        // The fast direction is across the wall (x), the slow one along it (z).
        EXPECT_GT(std::fabs(r.hess_axis.z), 0.95f) << x;
        EXPECT_LT(r.hess_slow, 0.1f * r.hess_fast) << x;
        // Relative Hessian: |A''| / A (0.99 of it, the rest is the normalisation's floor).
        EXPECT_NEAR(r.hess_fast, 0.99 * std::fabs(a2) / a, 0.3 * std::fabs(a2) / a)
            << "x = " << x << ": " << r.hess_fast << " vs " << std::fabs(a2) / a;
    }
}

TEST(Hessian, CacheRendersWithEllipsesWithoutMissesAndTheirFilesRoundTrip) {
    Scene s = load_scene(test::cornell_scene(), {"camera.resolution=[40,40]", "render.spp=1", "render.gi=\"cache\"", "render.rays=256",
                                                 "render.metric=\"hessian\"", "render.light_samples=4"});
    Stats stats;
    RenderResult r = render(s, {}, stats, nullptr);
    EXPECT_EQ(stats.to_json()["shading_misses"].get<double>(), 0.0);
    size_t ellipses = 0;
    for (size_t i = 0; i < r.cache->size(); ++i) {
        const Record& rec = r.cache->record(i);
        if (rec.radius_long > 0) {
            ++ellipses;
            EXPECT_GE(rec.radius_long, rec.radius);
            EXPECT_LE(rec.radius_long, s.render.cache.max_anisotropy * rec.radius * 1.0001f);
            EXPECT_NEAR(dot(rec.axis, rec.n), 0.0f, 1e-3f);  // in the tangent plane
        }
    }
    EXPECT_GT(ellipses, r.cache->size() / 10);
    CacheFile f = r.cache->to_file(r.cache_info);
    CacheFile back = parse_cache_file(serialize_cache_file(f), "mem");
    EXPECT_EQ(serialize_cache_file(back), serialize_cache_file(f));
    ASSERT_EQ(back.records.size(), f.records.size());
    EXPECT_EQ(back.records[0].axis, f.records[0].axis);
    EXPECT_EQ(back.records[0].radius_long, f.records[0].radius_long);
}

}  // namespace
}  // namespace bounce
