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

TEST(DeepColour, OverCompositingTheSamplesInDepthOrderGivesTheBeauty) {
    test::TempDir d;
    const Image img = render_with_deep(box(true), d.file("c.deep.exr"));
    auto in = OIIO::ImageInput::open(d.file("c.deep.exr"));
    ASSERT_TRUE(in);
    const OIIO::ImageSpec& spec = in->spec();
    const auto channel = [&](const char* name) {
        for (int k = 0; k < spec.nchannels; ++k)
            if (spec.channelnames[static_cast<size_t>(k)] == name) return k;
        ADD_FAILURE() << "no channel " << name;
        return 0;
    };
    const int Z = channel("Z"), A = channel("A"), R = channel("R"), G = channel("G"), B = channel("B");
    OIIO::DeepData dd;
    ASSERT_TRUE(in->read_native_deep_image(0, 0, dd));
    const Layer* beauty = img.find("beauty");
    ASSERT_TRUE(beauty);
    int edges = 0;
    float worst = 0;
    for (int64_t p = 0; p < static_cast<int64_t>(spec.width) * spec.height; ++p) {
        const int n = static_cast<int>(dd.samples(p));
        std::vector<int> order(static_cast<size_t>(n));
        std::iota(order.begin(), order.end(), 0);
        std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return dd.deep_value(p, Z, a) < dd.deep_value(p, Z, b); });
        double c[3] = {0, 0, 0}, through = 1;
        for (int s : order) {
            const double a = dd.deep_value(p, A, s);
            c[0] += through * dd.deep_value(p, R, s), c[1] += through * dd.deep_value(p, G, s), c[2] += through * dd.deep_value(p, B, s);
            through *= 1 - a;
        }
        const float* want = &beauty->data[static_cast<size_t>(p) * 4];
        for (int ch = 0; ch < 3; ++ch) worst = std::max(worst, static_cast<float>(std::abs(c[ch] - want[ch]) / std::max(1.0f, want[ch])));
        EXPECT_NEAR(1 - through, want[3], 1e-5) << "alpha at pixel " << p;
        edges += n > 1;
    }
    EXPECT_LT(worst, 1e-5f);
    EXPECT_GT(edges, 10);  // pixels where several fragments share the coverage
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
