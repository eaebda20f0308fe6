// Deep output with colour (render.deep_colour): flattening its samples the way Nuke's deep
// tools do (over, front to back) gives the beauty's colour and alpha; bounce reads the file back
// as the same fragments as a deep file without colour.
#include <gtest/gtest.h>

#include <OpenImageIO/deepdata.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <numeric>

#include "bounce/render/render.h"
#include "test_util.h"

namespace bounce {
namespace {

/// The mirror/glass box: edges of several objects in one pixel, reflections, refraction.
Scene box(bool colour) {
    return load_scene(test::source_dir() + "/scenes/cornell/mirror-glass.json",
                      {"camera.resolution=[24,24]", "render.spp=4", "render.rays=32", "render.gi=cache",
                       std::string("render.deep_colour=") + (colour ? "true" : "false")});
}

Image render_with_deep(const Scene& s, const std::string& deep_out) {
    RenderRequest request;
    request.deep_out = deep_out;
    Stats stats;
    return render(s, request, stats, nullptr).image;
}

struct Flattened {
    float worst = 0;  ///< largest colour difference (relative above 1) from the beauty
    float worst_alpha = 0;
    int edges = 0;  ///< pixels of several samples
};

/// Renders `s` with a deep colour file and flattens its samples over, front to back.
Flattened flatten(const Scene& s) {
    test::TempDir d;
    Flattened f;
    const Image img = render_with_deep(s, d.file("c.deep.exr"));
    auto in = OIIO::ImageInput::open(d.file("c.deep.exr"));
    if (!in) return ADD_FAILURE() << "no deep file", f;
    const OIIO::ImageSpec& spec = in->spec();
    const auto channel = [&](const char* name) {
        for (int k = 0; k < spec.nchannels; ++k)
            if (spec.channelnames[static_cast<size_t>(k)] == name) return k;
        ADD_FAILURE() << "no channel " << name;
        return 0;
    };
    const int Z = channel("Z"), A = channel("A"), R = channel("R"), G = channel("G"), B = channel("B");
    OIIO::DeepData dd;
    if (!in->read_native_deep_image(0, 0, dd)) return ADD_FAILURE() << "unreadable deep file", f;
    const Layer* beauty = img.find("beauty");
    if (!beauty) return ADD_FAILURE() << "no beauty", f;
    for (int64_t p = 0; p < static_cast<int64_t>(spec.width) * spec.height; ++p) {
        const int n = static_cast<int>(dd.samples(p));
        std::vector<int> order(static_cast<size_t>(n));
        std::iota(order.begin(), order.end(), 0);
        std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return dd.deep_value(p, Z, a) < dd.deep_value(p, Z, b); });
        double c[3] = {0, 0, 0}, through = 1;
        for (int k : order) {
            const double a = dd.deep_value(p, A, k);
            c[0] += through * dd.deep_value(p, R, k), c[1] += through * dd.deep_value(p, G, k), c[2] += through * dd.deep_value(p, B, k);
            through *= 1 - a;
        }
        const float* want = &beauty->data[static_cast<size_t>(p) * 4];
        for (int ch = 0; ch < 3; ++ch)
            f.worst = std::max(f.worst, static_cast<float>(std::abs(c[ch] - want[ch]) / std::max(1.0f, want[ch])));
        f.worst_alpha = std::max(f.worst_alpha, static_cast<float>(std::abs(1 - through - want[3])));
        f.edges += n > 1;
    }
    return f;
}

TEST(DeepColour, OverCompositingTheSamplesInDepthOrderGivesTheBeauty) {
    const Flattened f = flatten(box(true));
    EXPECT_LT(f.worst, 1e-5f);
    EXPECT_LT(f.worst_alpha, 1e-5f);
    EXPECT_GT(f.edges, 10);  // pixels where several fragments share the coverage
}

// Issue 61: a blended card's fragments (its coverage, and what is behind it) flatten to the beauty.
TEST(DeepColour, BlendedCutoutsFlattenToTheBeauty) {
    using nlohmann::json;
    const json scene = {
        {"camera", {{"position", {0, 1.6, -6}}, {"look_at", {0, 1, 0}}, {"fov", 45}, {"resolution", {24, 18}}}},
        {"render", {{"spp", 4}, {"light_samples", 2}, {"rays", 16}, {"gi", "brute"}, {"deep_colour", true}}},
        {"materials",
         {{"white", {{"color", 0.7}}},
          {"leaf", {{"color", {0.2, 0.6, 0.1}}, {"opacity", 0.4}}},
          {"glass", {{"color", 0.5}, {"opacity", 0.7}}}}},
        {"lights", {{{"type", "point"}, {"position", {0.3, 4, -3}}, {"color", 30}}}},
        {"objects",
         {{{"type", "quad"}, {"material", "white"}, {"vertices", {{-6, 0, -6}, {-6, 0, 6}, {6, 0, 6}, {6, 0, -6}}}},
          {{"type", "quad"}, {"material", "white"}, {"vertices", {{-6, 0, 3}, {6, 0, 3}, {6, 6, 3}, {-6, 6, 3}}}},
          {{"type", "quad"}, {"material", "leaf"}, {"vertices", {{-1, 0.2, 0}, {1, 0.2, 0}, {1, 2.2, 0}, {-1, 2.2, 0}}}},
          {{"type", "quad"}, {"material", "glass"}, {"vertices", {{-0.5, 0.5, -1}, {1.5, 0.5, -1}, {1.5, 1.5, -1}, {-0.5, 1.5, -1}}}}}}};
    const Flattened f = flatten(test::scene_from(scene));
    EXPECT_LT(f.worst, 1e-6f);
    EXPECT_LT(f.worst_alpha, 1e-6f);
    EXPECT_GT(f.edges, 50);  // pixels of the cards hold their samples and the wall's behind
}

TEST(DeepColour, BounceReadsTheFileBackAsTheSameFragments) {
    test::TempDir d;
    const Image with = render_with_deep(box(true), d.file("c.deep.exr"));
    const Image without = render_with_deep(box(false), d.file("p.deep.exr"));
    EXPECT_TRUE(read_deep(d.file("c.deep.exr")) == read_deep(d.file("p.deep.exr")));
    // Asking for colour changes no layer of the image.
    ASSERT_EQ(with.layers.size(), without.layers.size());
    for (size_t i = 0; i < with.layers.size(); ++i) EXPECT_EQ(with.layers[i].data, without.layers[i].data) << with.layers[i].name;
}

}  // namespace
}  // namespace bounce
