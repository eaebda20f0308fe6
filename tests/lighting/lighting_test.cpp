// Direct lighting against closed forms: point, spot, distant, quad area light (Lambert's
// polygon formula), constant sky, and an emissive mesh equal to the same quad light.
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include "bounce/accel/accel.h"
#include "bounce/lighting/lighting.h"
#include "test_util.h"

namespace bounce {
namespace {

using nlohmann::json;
using test::base_scene;
using test::scene_from;

Color irradiance_at(const Scene& scene, const Vec3& p, const Vec3& n, int samples, uint64_t key = 1, uint32_t object = 0) {
    SceneAccel accel(scene, scene.render.lighting);
    DirectLighting lighting(scene, accel, scene.render.lighting);
    Counters c;
    return lighting.irradiance(p, n, object, RandomStream(scene.render.visibility.seed, key), samples, c);
}

TEST(DirectLighting, PointLightIsIntensityTimesCosineOverDistanceSquared) {
    json j = base_scene();
    const float I = 40.0f, h = 3.0f;
    j["lights"] = {{{"type", "point"}, {"position", {0, h, 0}}, {"color", {I, I / 2, I / 4}}}};
    Scene s = scene_from(j);
    for (float x : {0.0f, 1.0f, 2.5f, 7.0f}) {
        Vec3 p{x, 0, 0.5f};
        Vec3 to = Vec3(0, h, 0) - p;
        float r2 = dot(to, to), cos_t = h / std::sqrt(r2);
        Color e = irradiance_at(s, p, {0, 1, 0}, 1);
        EXPECT_NEAR(e.x, I * cos_t / r2, 1e-5f * I) << "x=" << x;
        EXPECT_NEAR(e.y, I / 2 * cos_t / r2, 1e-5f * I) << "x=" << x;
    }
    // Below the horizon of the normal: nothing.
    EXPECT_EQ(irradiance_at(s, {0, 0, 0}, {0, -1, 0}, 1).x, 0.0f);
}

TEST(DirectLighting, PointLightIsShadowedByAnOccluder) {
    json j = base_scene();
    j["lights"] = {{{"type", "point"}, {"position", {0, 4, 0}}, {"color", 10}}};
    j["objects"].push_back({{"type", "quad"}, {"vertices", {{-1, 2, -1}, {1, 2, -1}, {1, 2, 1}, {-1, 2, 1}}}});
    Scene s = scene_from(j);
    EXPECT_EQ(irradiance_at(s, {0, 0, 0}, {0, 1, 0}, 1).x, 0.0f);
    EXPECT_GT(irradiance_at(s, {3, 0, 0}, {0, 1, 0}, 1).x, 0.0f);
}

TEST(DirectLighting, SpotLightConeAndFalloff) {
    json j = base_scene();
    j["lights"] = {
        {{"type", "spot"}, {"position", {0, 1, 0}}, {"direction", {0, -1, 0}}, {"color", 1}, {"cone_angle", 30}, {"cone_falloff", 10}}};
    Scene s = scene_from(j);
    auto at_angle = [&](float deg) {
        float x = std::tan(deg * kPi / 180);
        return irradiance_at(s, {x, 0, 0}, {0, 1, 0}, 1).x;
    };
    float c20 = std::cos(20 * kPi / 180);
    EXPECT_NEAR(at_angle(20), c20 * c20 * c20, 1e-5f);  // I cos / r^2 with r = 1/cos
    EXPECT_EQ(at_angle(41), 0.0f);
    float mid = at_angle(35), full = std::pow(std::cos(35 * kPi / 180), 3.0f);
    EXPECT_NEAR(mid, 0.5f * full, 1e-4f);  // smoothstep at the middle of the edge is 1/2
}

TEST(DirectLighting, SpotCosinePowerDimsOffItsAxis) {
    // cosine_power p: intensity x cos^p of the angle from the axis (Cycles 3.4's spot is p = 1,
    // measured by bench/peers/light_units.py); the cone and its edge are as without it.
    for (const float p : {1.0f, 4.0f}) {
        json j = base_scene();
        j["lights"] = {{{"type", "spot"},
                        {"position", {0, 1, 0}},
                        {"direction", {0, -1, 0}},
                        {"color", 1},
                        {"cone_angle", 30},
                        {"cone_falloff", 10},
                        {"cosine_power", p}}};
        const Scene s = scene_from(j);
        const auto at_angle = [&](float deg) { return irradiance_at(s, {std::tan(deg * kPi / 180), 0, 0}, {0, 1, 0}, 1).x; };
        const float c20 = std::cos(20 * kPi / 180);
        EXPECT_NEAR(at_angle(20), c20 * c20 * c20 * std::pow(c20, p), 1e-5f) << p;
        EXPECT_NEAR(at_angle(0), 1.0f, 1e-6f) << p;  // on the axis: as without it
        EXPECT_EQ(at_angle(41), 0.0f) << p;
        const float c35 = std::cos(35 * kPi / 180);
        EXPECT_NEAR(at_angle(35), 0.5f * std::pow(c35, 3.0f + p), 1e-4f) << p;
    }
}

TEST(DirectLighting, DistantLightIsIrradianceTimesCosine) {
    json j = base_scene();
    Vec3 d = normalize(Vec3(1, -2, 0.5f));
    j["lights"] = {{{"type", "distant"}, {"direction", {d.x, d.y, d.z}}, {"color", 3}}};
    Scene s = scene_from(j);
    EXPECT_NEAR(irradiance_at(s, {0, 0, 0}, {0, 1, 0}, 1).x, 3 * -d.y, 1e-5f);
}

/// Irradiance at p (normal n) from a uniform Lambertian polygon of radiance L: Lambert's
/// contour formula E = L/2 * sum_i angle_i * (n . unit(v_i x v_i+1)).
float lambert_polygon(const std::vector<Vec3>& poly, const Vec3& p, const Vec3& n, float L) {
    float sum = 0;
    for (size_t i = 0; i < poly.size(); ++i) {
        Vec3 a = normalize(poly[i] - p), b = normalize(poly[(i + 1) % poly.size()] - p);
        float angle = std::acos(std::clamp(dot(a, b), -1.0f, 1.0f));
        sum += angle * dot(n, normalize(cross(a, b)));
    }
    return std::abs(0.5f * L * sum);
}

TEST(DirectLighting, QuadLightMatchesAnalyticFormFactor) {
    json j = base_scene();
    Vec3 corner{-0.5f, 2, -0.3f}, eu{1.2f, 0, 0}, ev{0, 0, 0.8f};  // emits along eu x ev = -y
    j["lights"] = {{{"type", "quad"},
                    {"corner", {corner.x, corner.y, corner.z}},
                    {"edge_u", {eu.x, eu.y, eu.z}},
                    {"edge_v", {ev.x, ev.y, ev.z}},
                    {"color", 5}}};
    Scene s = scene_from(j);
    std::vector<Vec3> poly = {corner, corner + eu, corner + eu + ev, corner + ev};
    for (Vec3 p : {Vec3(0, 0, 0), Vec3(1.5f, 0, 0.7f), Vec3(-2, 0, 3)}) {
        float expected = lambert_polygon(poly, p, {0, 1, 0}, 5);
        float got = irradiance_at(s, p, {0, 1, 0}, 64 * 64).x;
        // 4096 stratified samples of a smooth integrand: error well below 0.2%.
        EXPECT_NEAR(got, expected, 2e-3f * expected) << p.x << "," << p.z;
    }
    // Tilted receiver.
    Vec3 n = normalize(Vec3(0.4f, 1, -0.2f));
    EXPECT_NEAR(irradiance_at(s, {0.3f, 0, 0.1f}, n, 4096).x, lambert_polygon(poly, {0.3f, 0, 0.1f}, n, 5),
                2e-3f * lambert_polygon(poly, {0.3f, 0, 0.1f}, n, 5));
}

TEST(DirectLighting, EmissiveMeshEqualsQuadLightOfSameShape) {
    json j = base_scene();
    j["materials"] = {{"glow", {{"emission", {2, 3, 4}}}}};
    j["objects"].push_back(
        {{"type", "quad"}, {"material", "glow"}, {"vertices", {{-0.5, 2, -0.3}, {0.7, 2, -0.3}, {0.7, 2, 0.5}, {-0.5, 2, 0.5}}}});
    Scene s = scene_from(j);
    ASSERT_EQ(s.lights.size(), 1u);
    std::vector<Vec3> poly = {{-0.5f, 2, -0.3f}, {0.7f, 2, -0.3f}, {0.7f, 2, 0.5f}, {-0.5f, 2, 0.5f}};
    Vec3 p{0.9f, 0, 0.2f};
    Color got = irradiance_at(s, p, {0, 1, 0}, 4096);
    EXPECT_NEAR(got.y, lambert_polygon(poly, p, {0, 1, 0}, 3), 3e-3f * got.y);
    EXPECT_NEAR(got.z / got.x, 2.0f, 1e-4f);
}

TEST(DirectLighting, ConstantSkyOnOpenPlaneIsPiTimesRadiance) {
    json j = base_scene();
    j["lights"] = {{{"type", "sky"}, {"color", {0.5, 1, 2}}}};
    Scene s = scene_from(j);
    Color e = irradiance_at(s, {0, 0, 0}, {0, 1, 0}, 64);
    EXPECT_NEAR(e.x, kPi * 0.5f, 1e-4f);
    EXPECT_NEAR(e.z, kPi * 2.0f, 1e-4f);
}

TEST(DirectLighting, StratifiedQuadErrorFallsWithSampleCount) {
    json j = base_scene();
    j["lights"] = {{{"type", "quad"}, {"corner", {-1, 1, -1}}, {"edge_u", {2, 0, 0}}, {"edge_v", {0, 0, 2}}, {"color", 1}}};
    Scene s = scene_from(j);
    std::vector<Vec3> poly = {{-1, 1, -1}, {-1, 1, 1}, {1, 1, 1}, {1, 1, -1}};
    Vec3 p{1.3f, 0, 0.4f};
    float exact = lambert_polygon(poly, p, {0, 1, 0}, 1);
    auto rms = [&](int n) {
        double e2 = 0;
        for (uint64_t k = 0; k < 64; ++k) {
            double d = irradiance_at(s, p, {0, 1, 0}, n, k).x - exact;
            e2 += d * d;
        }
        return std::sqrt(e2 / 64);
    };
    // Jittered stratification of a smooth integrand converges at least like 1/N (2D): going
    // from 16 to 256 samples must cut the RMS error by well over sqrt(16) = 4.
    EXPECT_GT(rms(16) / rms(256), 8.0);
}

/// A 2x1 RGB EXR: the left texel white, the right one black.
std::string half_white(const test::TempDir& d) {
    const std::string path = d.file("half.exr");
    auto out = OIIO::ImageOutput::create(path);
    OIIO::ImageSpec spec(2, 1, 3, OIIO::TypeDesc::FLOAT);
    const float px[6] = {1, 1, 1, 0, 0, 0};
    EXPECT_TRUE(out && out->open(path, spec) && out->write_image(OIIO::TypeDesc::FLOAT, px) && out->close());
    return path;
}

TEST(DirectLighting, ATexturedQuadLightEmitsOnlyWhereItsTextureIsLit) {
    test::TempDir d;
    json j = base_scene();
    j["lights"] = {{{"type", "quad"},
                    {"corner", {-1, 1, -1}},
                    {"edge_u", {2, 0, 0}},
                    {"edge_v", {0, 0, 2}},
                    {"color", 1},
                    {"texture", half_white(d)}}};
    const Scene s = scene_from(j);
    const Vec3 p{0.4f, 0, 0.3f};
    // Only the half with u < 0.5 (x < 0) emits: the irradiance of that polygon alone.
    const float exact = lambert_polygon({{-1, 1, -1}, {-1, 1, 1}, {0, 1, 1}, {0, 1, -1}}, p, {0, 1, 0}, 1);
    EXPECT_NEAR(irradiance_at(s, p, {0, 1, 0}, 1024).x, exact, 0.01f * exact);
}

TEST(DirectLighting, ASpotProjectsItsSlideAndStopsAtItsBarnDoors) {
    test::TempDir d;
    json j = base_scene();
    const json spot = {{"type", "spot"}, {"position", {0, 1, 0}}, {"direction", {0, -1, 0}},
                       {"color", 2},     {"cone_angle", 40},      {"cone_falloff", 0}};
    auto lit = [&](const json& extra, float z) {
        json l = spot;
        l.update(extra);
        j["lights"] = json::array({l});
        return irradiance_at(scene_from(j), {0, 0, z}, {0, 1, 0}, 1).x;
    };
    auto full = [](float z) { return 2 / (1 + z * z) / std::sqrt(1 + z * z); };  // I cos / r^2
    // Pointing down, the spot's right is +z: the slide's white left half falls on z < 0.
    const json slide = {{"texture", half_white(d)}};
    EXPECT_NEAR(lit(slide, -0.3f), full(-0.3f), 1e-6f);
    EXPECT_EQ(lit(slide, 0.3f), 0.0f);
    // The right barn door at 10 degrees: 0.1 (5.7 degrees) is lit, 0.3 (16.7) is not; the left is open.
    const json doors = {{"barn_doors", {90, 10, 90, 90}}};
    EXPECT_NEAR(lit(doors, 0.1f), full(0.1f), 1e-6f);
    EXPECT_EQ(lit(doors, 0.3f), 0.0f);
    EXPECT_NEAR(lit(doors, -0.3f), full(-0.3f), 1e-6f);
    // A key another type reads is refused with the type's keys.
    j["lights"] = {{{"type", "point"}, {"position", {0, 1, 0}}, {"barn_doors", {1, 2, 3, 4}}}};
    EXPECT_THROW(scene_from(j), InputError);
}

}  // namespace
}  // namespace bounce
