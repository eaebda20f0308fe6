// Shading with cached irradiance (issue #7): the (radiance, direction) model against its
// exact diffuse limit, bump mapping against an analytic surface, the GGX lobe against its
// closed form, and renders: bump strength 0 is the un-bumped image, glossy highlights follow
// the light's direction as an occluder moves, and gloss or bumps do not invalidate a cache.
#include <gtest/gtest.h>

#include "bounce/core/error.h"
#include "bounce/render/render.h"
#include "bounce/shade/brdf.h"
#include "test_util.h"

namespace bounce {
namespace {

using nlohmann::json;

TEST(ShadingModel, DiffuseIsExactlyAlbedoTimesEOverPiWhateverTheDirection) {
    RandomStream rng(3, 4);
    const Vec3 n = normalize(Vec3(0.3f, 1, -0.2f));
    for (uint64_t i = 0; i < 500; ++i) {
        Indirect in;
        in.irradiance = {rng.get(i, 0) * 5, rng.get(i, 1), rng.get(i, 2) * 0.1f};
        for (uint32_t c = 0; c < 3; ++c)  // any directions, grazing and below the surface included
            in.light_dir[c] = i % 7 == 0 ? Vec3(0) : Vec3(rng.get(i, 3 + c) - 0.5f, rng.get(i, 6 + c) - 0.5f, rng.get(i, 9 + c) - 0.5f);
        SurfaceShading s;
        s.albedo = {rng.get(i, 12), rng.get(i, 13), rng.get(i, 14)};
        s.normal = n;
        const Vec3 wo = normalize(Vec3(0.1f, 1, 0.4f));
        const Color want = s.albedo * in.irradiance * kInvPi;
        for (bool per_channel : {false, true}) {
            Color got = indirect_radiance(in, n, s, wo, per_channel);
            for (int c = 0; c < 3; ++c) EXPECT_EQ(got[c], want[c]) << i << " channel " << c;
        }
    }
}

TEST(ShadingModel, BumpedNormalTiltsTowardTheHeightGradient) {
    // Plane P = (u, v, 0): P + h n with h = a u + b v has normal (-a, -b, 1) / |.|.
    const Vec3 n(0, 0, 1), dpdu(1, 0, 0), dpdv(0, 1, 0);
    for (auto [a, b] : {std::pair{0.5f, 0.0f}, std::pair{-0.2f, 0.7f}, std::pair{2.0f, -1.0f}}) {
        Vec3 want = normalize(Vec3(-a, -b, 1)), got = bumped_normal(n, dpdu, dpdv, a, b);
        EXPECT_NEAR(got.x, want.x, 1e-6f);
        EXPECT_NEAR(got.y, want.y, 1e-6f);
        EXPECT_NEAR(got.z, want.z, 1e-6f);
        // A uv orientation flipped against n (dpdv -> -dpdv, so h_v flips too) gives the same normal.
        Vec3 flipped = bumped_normal(n, dpdu, -dpdv, a, -b);
        EXPECT_NEAR(dot(flipped, want), 1.0f, 1e-6f);
    }
    EXPECT_EQ(bumped_normal(n, dpdu, dpdv, 0, 0), n);
}

TEST(ShadingModel, GgxMatchesItsClosedFormAndIsReciprocal) {
    const Vec3 n(0, 1, 0);
    for (float r : {0.2f, 0.5f, 1.0f}) {
        // Normal incidence and view: D = 1 / (pi alpha^2), V = 1/4, F = F0.
        const float a = r * r;
        Color f = ggx_specular(n, n, n, Color(0.5f), r);
        EXPECT_NEAR(f.x, 0.5f / (4 * kPi * a * a), 1e-4f * f.x);
        const Vec3 wo = normalize(Vec3(0.3f, 0.8f, -0.1f)), wi = normalize(Vec3(-0.5f, 0.4f, 0.6f));
        EXPECT_NEAR(ggx_specular(n, wo, wi, Color(0.3f), r).y, ggx_specular(n, wi, wo, Color(0.3f), r).y, 1e-6f);
        EXPECT_EQ(ggx_specular(n, wo, -wi, Color(1), r).x, 0.0f);  // below the surface
    }
}

TEST(ShadingModel, SphereUvsAreContinuousOnEveryTriangle) {
    TriangleMesh m = make_icosphere({1, 2, 3}, 2, 3, 0);
    ASSERT_EQ(m.uvs.size(), m.positions.size());
    for (size_t t = 0; t < m.triangle_count(); ++t) {
        float lo = 2, hi = -2;
        for (int k = 0; k < 3; ++k) {
            float u = m.uvs[m.indices[3 * t + static_cast<size_t>(k)]].x;
            lo = std::min(lo, u), hi = std::max(hi, u);
        }
        EXPECT_LT(hi - lo, 0.25f) << "triangle " << t << " spans the seam";
        Vec3 dpdu, dpdv;
        EXPECT_TRUE(triangle_tangents(m, static_cast<uint32_t>(t), dpdu, dpdv));
    }
}

/// The showcase scene (bumped glossy sphere lit by bounce light only), small and quick.
Scene showcase(const std::vector<std::string>& extra = {}) {
    std::vector<Override> o = {"camera.resolution=[48,48]", "render.spp=1", "render.rays=64", "render.threads=2"};
    o.insert(o.end(), extra.begin(), extra.end());
    return load_scene(test::source_dir() + "/scenes/cornell/glossy-bump.json", o);
}

std::vector<float> beauty(const Scene& s, RenderRequest req = {}, const std::string& cache_out = "") {
    Stats stats;
    RenderResult r = render(s, req, stats, nullptr);
    if (!cache_out.empty()) write_cache_file(cache_out, r.cache->to_file(r.cache_info));
    return r.image.find("beauty")->data;
}

TEST(ShadingRender, BumpStrengthZeroIsTheUnbumpedImage) {
    auto plain = beauty(showcase({"materials.gold.bump_texture=\"\""}));
    EXPECT_EQ(beauty(showcase({"materials.gold.bump_strength=0"})), plain);
    EXPECT_NE(beauty(showcase()), plain);  // and the bumps do show
}

/// A black glossy floor under a white card lit from below, half of the card hidden from the
/// floor by a black occluder: the floor's beauty is its glossy reflection of the indirect light
/// alone (no diffuse part, no direct light), so it shows where that light comes from.
double highlight_centroid_x(float occluder_x0, float occluder_x1) {
    json j = {
        {"camera", {{"position", {0, 0.9, 3.0}}, {"look_at", {0, 0, 0}}, {"fov", 60}, {"resolution", {40, 30}}}},
        {"render", {{"spp", 1}, {"gi", "brute"}, {"rays", 256}, {"light_samples", 1}}},
        {"materials",
         {{"floor", {{"color", 0.0}, {"specular", 1.0}, {"roughness", 0.35}}}, {"card", {{"color", 1.0}}}, {"black", {{"color", 0.0}}}}},
        {"objects",
         {{{"type", "quad"}, {"material", "floor"}, {"vertices", {{-3, 0, -3}, {-3, 0, 3}, {3, 0, 3}, {3, 0, -3}}}},
          {{"type", "quad"}, {"material", "card"}, {"vertices", {{-4, 2, -4}, {4, 2, -4}, {4, 2, 4}, {-4, 2, 4}}}},
          {{"type", "quad"},
           {"material", "black"},
           {"vertices", {{occluder_x0, 1.2, -4}, {occluder_x1, 1.2, -4}, {occluder_x1, 1.2, 4}, {occluder_x0, 1.2, 4}}}}}},
        // A spot pointing up: the floor gets no direct light, so no direct highlight.
        {"lights",
         {{{"type", "spot"},
           {"position", {0, 1.9, 0}},
           {"direction", {0, 1, 0}},
           {"cone_angle", 80},
           {"cone_falloff", 5},
           {"color", 30.0}}}}};
    Stats stats;
    Image img = render(test::scene_from(j), {}, stats, nullptr).image;
    const Layer& b = *img.find("beauty");
    double sum = 0, sx = 0;
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) {
            const float* p = img.at(b, x, y);
            double l = p[0] + p[1] + p[2];
            sum += l, sx += l * x;
        }
    EXPECT_GT(sum, 0.1);
    return sx / sum;
}

TEST(ShadingRender, GlossyHighlightsMoveWithTheOccluder) {
    const double light_from_right = highlight_centroid_x(-4, 0), light_from_left = highlight_centroid_x(0, 4);
    // Mirror images about the image centre (x = 19.5 of 40 pixels), each well off it.
    EXPECT_GT(light_from_right, 19.5 + 1.5);
    EXPECT_LT(light_from_left, 19.5 - 1.5);
    EXPECT_NEAR(light_from_right - 19.5, 19.5 - light_from_left, 0.5);  // up to sampling noise
}

TEST(ShadingRender, GlossAndBumpsKeepACacheValidButAlbedoMakesItsBounceLightStale) {
    test::TempDir d;
    beauty(showcase(), {}, d.file("c.bic"));
    RenderRequest reuse;
    reuse.cache_in = d.file("c.bic");
    Stats stats;
    // Gloss and bumps do not change what a record holds; an albedo does (the light the other
    // surfaces send): the records are kept and said to be stale.
    EXPECT_FALSE(
        render(showcase({"materials.gold.roughness=0.8", "materials.gold.bump_strength=1"}), reuse, stats, nullptr).cache_other_lighting);
    EXPECT_TRUE(render(showcase({"materials.white.color=0.5"}), reuse, stats, nullptr).cache_other_lighting);
}

}  // namespace
}  // namespace bounce
