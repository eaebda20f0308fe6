// Colour for screens (core/display.h): the built-in sRGB curve, an OpenColorIO config's display
// and view on known pixels (tests/data/ocio/config.ocio: swap-sqrt swaps red and blue and takes
// the square root, half halves), the OCIO variable, refusals, the CLI's PNG and the tool's view.
#include <OpenImageIO/imageio.h>

#include <cmath>

#include "bounce/core/display.h"
#include "bounce/core/image.h"
#include "bounce/tool/session.h"
#include "test_util.h"

namespace bounce {
namespace {

std::string config() { return test::source_dir() + "/tests/data/ocio/config.ocio"; }

/// A 1x1 beauty layer holding `rgb`, through `display` after `exposure` stops.
std::array<int, 3> shown(const DisplayTransform& display, std::array<float, 3> rgb, float exposure = 0) {
    Image img;
    img.full_width = img.width = img.full_height = img.height = 1;
    Layer& l = img.add_layer("beauty", {"R", "G", "B"});
    l.data.assign(rgb.begin(), rgb.end());
    const std::vector<uint8_t> out = display_rgb8(img, l, exposure, display);
    return {out[0], out[1], out[2]};
}

/// The swap-sqrt view by hand, as 8-bit.
std::array<int, 3> swap_sqrt(const float* rgb) {
    const auto byte = [](float v) { return static_cast<int>(std::lround(std::sqrt(std::clamp(v, 0.0f, 1.0f)) * 255)); };
    return {byte(rgb[2]), byte(rgb[1]), byte(rgb[0])};
}

TEST(Display, WithoutAConfigItIsTheSrgbCurve) {
    const DisplayTransform builtin(DisplaySettings{}, nullptr);
    EXPECT_TRUE(builtin.builtin());
    for (const float v : {-1.0f, 0.0f, 0.002f, 0.18f, 0.5f, 1.0f, 7.0f}) {
        const auto px = shown(builtin, {v, v / 2, v / 4}, 1.0f);
        EXPECT_EQ(px, (std::array<int, 3>{srgb8(2 * v), srgb8(v), srgb8(v / 2)})) << v;
    }
}

TEST(Display, TheConfigsDefaultViewIsAppliedToKnownPixels) {
    const DisplayTransform t(DisplaySettings{config(), "", ""}, nullptr);
    EXPECT_FALSE(t.builtin());
    EXPECT_EQ(t.name(), config() + ": test / swap-sqrt");
    EXPECT_EQ(shown(t, {0.36f, 0.04f, 0.64f}), (std::array<int, 3>{204, 51, 153}));
    EXPECT_EQ(shown(t, {0.09f, 0.01f, 0.16f}, 2.0f), (std::array<int, 3>{204, 51, 153}));  // exposure first
    EXPECT_EQ(shown(t, {4.0f, -1.0f, 0.0f}), (std::array<int, 3>{0, 0, 255}));             // clamped after
}

TEST(Display, ADisplayAndViewAreChosenByName) {
    EXPECT_EQ(shown(DisplayTransform({config(), "other", ""}, nullptr), {0.36f, 0.04f, 0.64f}), (std::array<int, 3>{46, 5, 82}));
    EXPECT_EQ(shown(DisplayTransform({config(), "test", "raw"}, nullptr), {0.36f, 0.04f, 0.64f}), (std::array<int, 3>{92, 10, 163}));
}

TEST(Display, TheOcioVariableNamesTheConfigUnlessOneIsGiven) {
    EXPECT_EQ(shown(DisplayTransform({}, config().c_str()), {0.36f, 0.04f, 0.64f}), (std::array<int, 3>{204, 51, 153}));
    EXPECT_EQ(shown(DisplayTransform({config(), "other", ""}, "/no/such.ocio"), {0.36f, 0.04f, 0.64f}), (std::array<int, 3>{46, 5, 82}));
    EXPECT_TRUE(DisplayTransform({}, "").builtin());
}

TEST(Display, BadConfigsDisplaysAndViewsAreRefusedByName) {
    test::TempDir d;
    const auto refused = [](const DisplaySettings& s, const char* env, const std::vector<std::string>& parts) {
        try {
            DisplayTransform t(s, env);
            ADD_FAILURE() << "taken: " << s.config << " " << s.display << " " << s.view;
        } catch (const InputError& e) {
            for (const auto& p : parts) EXPECT_NE(std::string(e.what()).find(p), std::string::npos) << e.what() << " lacks " << p;
        }
    };
    refused({d.file("none.ocio"), "", ""}, nullptr, {d.file("none.ocio")});
    refused({}, d.file("none.ocio").c_str(), {d.file("none.ocio")});
    refused({d.write("bad.ocio", "ocio_profile_version: 2\ncolorspaces: [[[\n"), "", ""}, nullptr,
            {d.file("bad.ocio"), "not a usable OpenColorIO config"});
    refused({config(), "nope", ""}, nullptr, {config(), "display", "no display 'nope'; the config has: test, other"});
    refused({config(), "other", "swap-sqrt"}, nullptr, {config(), "view", "no view 'swap-sqrt'; the config has: half"});
    refused({"", "", "half"}, nullptr, {"command line", "--view"});
    refused({d.path().string(), "", ""}, nullptr, {d.path().string()});  // a folder
}

/// The PNG beside a render is the EXR's beauty through the view; the EXR stays scene-linear and
/// says its primaries.
TEST(Display, TheCliWritesThePngThroughTheView) {
    test::TempDir d;
    const std::string common = test::cornell_scene() + " --res 24x20 --spp 1 --gi none -q";
    ASSERT_EQ(test::run_bounce("render " + common + " -o " + d.file("a.exr") + " --ocio-config " + config()), 0);
    ASSERT_EQ(test::run_bounce_shell("OCIO=" + config() + " " + BOUNCE_BINARY + " render " + common + " -o " + d.file("b.exr")), 0);
    ASSERT_EQ(test::run_bounce("render " + common + " -o " + d.file("c.exr")), 0);
    const Image exr = read_exr(d.file("a.exr"));
    const Layer* beauty = exr.find("beauty");
    ASSERT_TRUE(beauty);
    const auto png = [](const std::string& path) {
        auto in = OIIO::ImageInput::open(path);
        std::vector<uint8_t> px(static_cast<size_t>(in->spec().width) * in->spec().height * 3);
        EXPECT_TRUE(in->read_image(0, 0, 0, 3, OIIO::TypeDesc::UINT8, px.data()));
        return px;
    };
    const std::vector<uint8_t> a = png(d.file("a.png")), c = png(d.file("c.png"));
    EXPECT_EQ(png(d.file("b.png")), a);
    size_t lit = 0;
    for (size_t p = 0; p < a.size() / 3; ++p) {
        const float* rgb = &beauty->data[p * beauty->channels.size()];
        const auto want = swap_sqrt(rgb);
        for (int k = 0; k < 3; ++k) EXPECT_NEAR(a[3 * p + k], want[k], 1) << p;  // OCIO's pow is approximate
        for (int k = 0; k < 3; ++k) EXPECT_EQ(c[3 * p + k], srgb8(rgb[k])) << p;
        lit += rgb[0] > 0.05f && std::abs(rgb[0] - rgb[2]) > 0.05f;
    }
    EXPECT_GT(lit, 50u);  // the red and green walls tell a swap from none
    auto in = OIIO::ImageInput::open(d.file("a.exr"));
    const OIIO::ParamValue* chroma = in->spec().find_attribute("chromaticities");
    ASSERT_TRUE(chroma);
    const float* xy = static_cast<const float*>(chroma->data());
    EXPECT_EQ(std::vector<float>(xy, xy + 8), (std::vector<float>{0.64f, 0.33f, 0.30f, 0.60f, 0.15f, 0.06f, 0.3127f, 0.3290f}));
    test::expect_refused("render " + common + " -o " + d.file("e.exr") + " --ocio-config " + d.file("no.ocio"), {d.file("no.ocio")});
    test::expect_refused("render " + common + " -o " + d.file("e.exr") + " --ocio-config " + config() + " --display nope",
                         {config(), "display", "nope"});
    test::expect_refused("render " + common + " -o " + d.file("e.exr") + " --view half", {"command line", "--view"});
    EXPECT_FALSE(std::filesystem::exists(d.file("e.exr")));
}

TEST(Display, TheToolsViewGoesThroughTheView) {
    test::TempDir d;
    SessionOptions o;
    o.scene = test::cornell_scene();
    o.out_dir = d.file("out");
    o.threads = 2;
    o.sets = {"camera.resolution=[16,12]", "render.spp=1", "render.gi=none"};
    o.default_to_cache = false;
    o.display = std::make_shared<const DisplayTransform>(DisplaySettings{config(), "", ""}, nullptr);
    LightingSession s(o);
    s.start(SessionAction::Rasterize, std::nullopt);
    s.wait();
    ASSERT_EQ(s.status()["state"], "done") << s.status()["message"];
    const Image img = s.image();
    const Layer* beauty = img.find("beauty");
    const LightingSession::Pixels px = s.pixels("beauty", 0);
    ASSERT_EQ(px.rgba.size(), static_cast<size_t>(4 * img.width * img.height));
    for (size_t p = 0; p < static_cast<size_t>(img.width * img.height); ++p) {
        const auto want = swap_sqrt(&beauty->data[p * beauty->channels.size()]);
        for (int k = 0; k < 3; ++k) EXPECT_NEAR(static_cast<uint8_t>(px.rgba[4 * p + k]), want[k], 1) << p;
    }
}

}  // namespace
}  // namespace bounce
