// Deep buffer round trips, shading from a loaded deep file, crop and thread-count invariance,
// and the Cornell box's image statistics.
#include <gtest/gtest.h>
#include <fmt/format.h>
#include <tbb/task_arena.h>

#include "bounce/core/image.h"
#include "bounce/render/render.h"
#include "test_util.h"

namespace bounce {
namespace {

Scene small_cornell(const std::vector<std::string>& extra = {}) {
    std::vector<Override> o = {"camera.resolution=[48,48]", "render.spp=4", "render.light_samples=4"};
    o.insert(o.end(), extra.begin(), extra.end());
    return load_scene(test::cornell_scene(), o);
}

RenderResult render_quiet(const Scene& s, const RenderRequest& req = {}) {
    Stats stats;
    return render(s, req, stats, nullptr);
}

RenderRequest writing_deep(const std::string& path) {
    RenderRequest r;
    r.deep_out = path;
    return r;
}

RenderRequest reading_deep(const std::string& path) {
    RenderRequest r;
    r.deep_in = path;
    return r;
}

void expect_same_layers(const Image& a, const Image& b) {
    ASSERT_EQ(a.layers.size(), b.layers.size());
    for (size_t i = 0; i < a.layers.size(); ++i) {
        EXPECT_EQ(a.layers[i].channels, b.layers[i].channels);
        EXPECT_TRUE(a.layers[i].data == b.layers[i].data) << "layer " << a.layers[i].name << " differs";
    }
}

TEST(DeepBuffer, RoundTripIsBitExact) {
    test::TempDir dir;
    Scene s = small_cornell({"render.crop=[5,40,7,30]"});
    RenderResult r = render_quiet(s, writing_deep(dir.file("deep.exr")));
    ASSERT_GT(r.deep.fragments.size(), 500u);
    DeepBuffer back = read_deep(dir.file("deep.exr"));
    EXPECT_EQ(back.x0, 5);
    EXPECT_EQ(back.y0, 7);
    EXPECT_EQ(back.full_width, 48);
    EXPECT_TRUE(back == r.deep);
}

TEST(DeepBuffer, ShadingFromLoadedDeepGivesTheSameImage) {
    test::TempDir dir;
    Scene s = small_cornell();
    RenderResult direct = render_quiet(s, writing_deep(dir.file("deep.exr")));
    RenderResult reshaded = render_quiet(s, reading_deep(dir.file("deep.exr")));
    expect_same_layers(direct.image, reshaded.image);
}

TEST(DeepBuffer, FragmentsCoverPixelsAndMergeSubsamples) {
    Scene s = small_cornell({"render.spp=16"});
    RenderResult r = render_quiet(s);
    // Coverage never exceeds the pixel; inside the box's opening it is exactly full.
    for (int y = 0; y < r.deep.height; ++y)
        for (int x = 0; x < r.deep.width; ++x) {
            float w = 0;
            for (const Fragment& f : r.deep.pixel(x, y)) w += f.weight;
            ASSERT_LE(w, 1.0f + 1e-6f);
            if (x > 4 && x < 44 && y > 4 && y < 44) {
                ASSERT_NEAR(w, 1.0f, 1e-6f) << x << "," << y;
            }
        }
    // Subsamples of one surface merge: far fewer fragments than subsamples.
    EXPECT_LT(r.deep.fragments.size(), 2 * r.deep.pixel_count());
}

TEST(DeepBuffer, FragmentsLieOnTheSurfaceAtARidge) {
    // A roof ridge along z: two faces sloping 10 degrees down from x = 0 (normals 20 degrees
    // apart, so subsamples on both merge). The centroid of a pixel straddling the ridge lies
    // below both faces, where a gather would see only the underside; a fragment must not.
    test::TempDir dir;
    const float t = std::tan(10 * kPi / 180);
    const std::string obj = dir.write("ridge.obj", fmt::format("v -10 {0} -10\nv -10 {0} 10\nv 0 0 10\nv 0 0 -10\n"
                                                               "v 10 {0} -10\nv 10 {0} 10\n"
                                                               "f 1 2 3\nf 1 3 4\nf 4 3 6\nf 4 6 5\n",
                                                               -10 * t));
    nlohmann::json j = test::base_scene();
    j["objects"] = {{{"file", obj}}};
    j["camera"]["position"] = {0.3, 10, 0.001};
    j["camera"]["look_at"] = {0.3, 0, 0};  // the ridge crosses pixel centres, not a pixel boundary
    j["render"] = {{"spp", 16}};
    Scene s = test::scene_from(j);
    RenderResult r = render_quiet(s);
    int merged = 0;
    for (int y = 0; y < r.deep.height; ++y)
        for (int x = 0; x < r.deep.width; ++x)
            for (const Fragment& f : r.deep.pixel(x, y)) {
                ASSERT_NEAR(f.p.y, -std::abs(f.p.x) * t, 1e-4f) << "pixel " << x << "," << y;
                // Faces' normals have |n.x| = sin(10 deg); a mean of both has less.
                if (std::abs(f.ng.x) < 0.9f * std::sin(10 * kPi / 180)) ++merged;
            }
    EXPECT_GE(merged, 8) << "the ridge's pixels should merge subsamples of both faces";
}

TEST(DeepBuffer, FragmentsLieWhereTheCameraSeesThemAroundACorner) {
    // A card just above the floor hides its quadrant x < 0, z < 0. Where the card's corner is
    // in a pixel, what the pixel sees of the floor is an L, whose centroid can lie under the
    // card: a gather there sees the card's underside (a dark speck beside a light's corner in
    // shot B's brute-force frames). Every floor fragment must lie where the floor is seen.
    const float pixel = 2 * std::tan(20 * kPi / 180) * 10 / 16;
    int shared = 0;
    for (float ox : {0.1f, 0.3f})
        for (float oz : {0.15f, 0.35f}) {
            nlohmann::json j = test::base_scene();
            j["objects"].push_back({{"type", "quad"}, {"vertices", {{-5, 0.01, -5}, {-5, 0.01, 0}, {0, 0.01, 0}, {0, 0.01, -5}}}});
            j["camera"]["position"] = {ox * pixel, 10, oz * pixel + 0.001f};
            j["camera"]["look_at"] = {ox * pixel, 0, oz * pixel};
            j["render"] = {{"spp", 16}};
            RenderResult r = render_quiet(test::scene_from(j));
            for (int y = 0; y < r.deep.height; ++y)
                for (int x = 0; x < r.deep.width; ++x) {
                    auto frags = r.deep.pixel(x, y);
                    shared += frags.size() > 1;
                    for (const Fragment& f : frags) {
                        if (f.object != 0) continue;
                        ASSERT_FALSE(f.p.x < -1e-4f && f.p.z < -1e-4f)
                            << "offset " << ox << "," << oz << " pixel " << x << "," << y << ": (" << f.p.x << ", " << f.p.z << ")";
                    }
                }
        }
    EXPECT_GE(shared, 8) << "pixels should see both the card and the floor";
}

TEST(DeepBuffer, FootprintIsPixelWidthOnAFrontalPlane) {
    // Back wall of the Cornell box (z = 559.2) seen head-on from z = -800: one pixel spans
    // 2 tan(fov/2) * distance / height.
    Scene s = small_cornell({"render.spp=1"});
    RenderResult r = render_quiet(s);
    const Fragment& f = r.deep.pixel(24, 20)[0];
    ASSERT_NEAR(f.p.z, 559.2f, 0.01f);
    float expected = 2 * std::tan(39.3077f * kPi / 360) * (559.2f + 800) / 48 / std::abs(normalize(f.p - s.camera.position).z);
    EXPECT_NEAR(f.footprint, expected, 0.02f * expected);
}

TEST(Render, CropMatchesTheSameWindowOfAFullRender) {
    Scene full = small_cornell();
    Scene crop = small_cornell({"render.crop=[10,30,5,25]"});
    Image a = render_quiet(full).image, b = render_quiet(crop).image;
    ASSERT_EQ(b.width, 20);
    for (size_t l = 0; l < a.layers.size(); ++l)
        for (int y = 0; y < b.height; ++y)
            for (int x = 0; x < b.width; ++x)
                for (size_t c = 0; c < a.layers[l].channels.size(); ++c)
                    ASSERT_EQ(a.at(a.layers[l], x + 10, y + 5)[c], b.at(b.layers[l], x, y)[c]);
}

TEST(Render, ImageDoesNotDependOnThreadCount) {
    Image one = render_quiet(small_cornell({"render.threads=1"})).image;
    Image two = render_quiet(small_cornell({"render.threads=2", "render.tile_size=7"})).image;
    Image eight = render_quiet(small_cornell({"render.threads=8", "render.tile_size=5"})).image;
    expect_same_layers(one, two);
    expect_same_layers(one, eight);
}

TEST(Render, SeedChangesTheNoiseOnly) {
    Image a = render_quiet(small_cornell({"render.seed=1"})).image;
    Image b = render_quiet(small_cornell({"render.seed=2"})).image;
    const Layer &la = *a.find("beauty"), &lb = *b.find("beauty");
    EXPECT_FALSE(la.data == lb.data);
    double ma = 0, mb = 0;
    for (size_t i = 0; i < la.data.size(); i += 4) ma += la.data[i], mb += lb.data[i];
    EXPECT_NEAR(ma / mb, 1.0, 0.02);
}

TEST(Render, CornellBoxDirectLightingStatistics) {
    Scene s = load_scene(test::cornell_scene(), {"camera.resolution=[64,64]", "render.spp=4", "render.light_samples=16"});
    Image img = render_quiet(s).image;
    const Layer& b = *img.find("beauty");
    double mean[3] = {0, 0, 0};
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x)
            for (int c = 0; c < 3; ++c) mean[c] += img.at(b, x, y)[c];
    for (double& m : mean) m /= img.width * img.height;
    // Regression values, measured with 1024 light samples at 64x64: (0.14530, 0.09899,
    // 0.03081). 16 samples stay within 0.1% of them; 1.5% allows for sampling changes.
    EXPECT_NEAR(mean[0], 0.14530, 0.015 * 0.14530);
    EXPECT_NEAR(mean[1], 0.09899, 0.015 * 0.09899);
    EXPECT_NEAR(mean[2], 0.03081, 0.015 * 0.03081);
    // Red wall on the left, green on the right.
    const float* left = img.at(b, 4, 32);
    const float* right = img.at(b, 59, 32);
    EXPECT_GT(left[0], 3 * left[1]);
    EXPECT_GT(right[1], 1.5f * right[0]);
}

/// Lambert's contour formula: irradiance at p (normal n) from a uniform polygon of radiance L.
float lambert_polygon(const std::vector<Vec3>& poly, const Vec3& p, const Vec3& n, float L) {
    float sum = 0;
    for (size_t i = 0; i < poly.size(); ++i) {
        Vec3 a = normalize(poly[i] - p), b = normalize(poly[(i + 1) % poly.size()] - p);
        sum += std::acos(std::clamp(dot(a, b), -1.0f, 1.0f)) * dot(n, normalize(cross(a, b)));
    }
    return std::abs(0.5f * L * sum);
}

TEST(Render, CornellBackWallMatchesTheLightsFormFactor) {
    // Upper back wall: unoccluded view of the ceiling light, so the direct layer must equal
    // albedo * L * F (Lambert's formula) up to the light-sampling error.
    Scene s = load_scene(test::cornell_scene(), {"camera.resolution=[64,64]", "render.spp=1", "render.light_samples=1024"});
    RenderResult r = render_quiet(s);
    std::vector<Vec3> light = {{343, 548.7f, 227}, {343, 548.7f, 332}, {213, 548.7f, 332}, {213, 548.7f, 227}};
    const Layer& direct = *r.image.find("direct");
    int checked = 0;
    for (int x : {20, 32, 44})
        for (int y : {17, 22}) {
            const Fragment& f = r.deep.pixel(x, y)[0];
            ASSERT_NEAR(f.p.z, 559.2f, 0.01f);
            float E_green = lambert_polygon(light, f.p, {0, 0, -1}, 12.0f);
            float expected = 0.71f * E_green / kPi;
            EXPECT_NEAR(r.image.at(direct, x, y)[1], expected, 0.01f * expected) << x << "," << y;
            ++checked;
        }
    EXPECT_EQ(checked, 6);
}

}  // namespace
}  // namespace bounce
