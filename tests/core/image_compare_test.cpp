// Image error metrics (bounce compare) on images with known differences, and brute-force
// renders through the command line.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include "bounce/core/image.h"
#include "bounce/core/image_compare.h"
#include "bounce/core/sequence_compare.h"
#include "bounce/core/error.h"
#include "test_util.h"

namespace bounce {
namespace {

Image flat(int w, int h, float value) {
    Image img;
    img.full_width = img.width = w, img.full_height = img.height = h;
    Layer& l = img.add_layer("indirect", {"indirect.R", "indirect.G", "indirect.B"});
    std::fill(l.data.begin(), l.data.end(), value);
    return img;
}

TEST(Compare, KnownErrors) {
    Image ref = flat(10, 10, 2.0f), test = flat(10, 10, 2.0f);
    // One pixel off by +1 in every channel, one by -3 in red only.
    float* p = test.at(test.layers[0], 3, 4);
    p[0] += 1, p[1] += 1, p[2] += 1;
    test.at(test.layers[0], 7, 7)[0] -= 3;
    auto e = compare_images(test, ref, "", "t.exr");
    ASSERT_EQ(e.size(), 1u);
    const double n = 300;
    EXPECT_NEAR(e[0].rmse, std::sqrt((3 * 1.0 + 9.0) / n), 1e-9);
    EXPECT_NEAR(e[0].rel_rmse, e[0].rmse / 2.0, 1e-9);
    EXPECT_NEAR(e[0].mean_abs, 6.0 / n, 1e-9);
    EXPECT_DOUBLE_EQ(e[0].max_abs, 3.0);
    EXPECT_NEAR(e[0].relmse, (3 * 1.0 / 4.01 + 9.0 / 4.01) / n, 1e-9);
    EXPECT_EQ(compare_images(ref, ref, "indirect", "r.exr")[0].rmse, 0.0);
}

TEST(Compare, BeautyWithTheReferencesDirectLightMeasuresOnlyIndirect) {
    // beauty = direct + indirect contribution; the two renders' direct light differs (their own
    // light samples), their indirect contributions differ by 0.5 at one pixel.
    auto render = [](float direct, float extra) {
        Image img;
        img.full_width = img.width = 4, img.full_height = img.height = 1;
        Layer& b = img.add_layer("beauty", {"R", "G", "B", "A"});
        Layer& d = img.add_layer("direct", {"direct.R", "direct.G", "direct.B"});
        for (int x = 0; x < 4; ++x)
            for (int c = 0; c < 3; ++c) {
                img.at(d, x, 0)[c] = direct * static_cast<float>(x + 1);
                img.at(b, x, 0)[c] = img.at(d, x, 0)[c] + 1.0f + (x == 2 ? extra : 0.0f);
            }
        for (int x = 0; x < 4; ++x) img.at(b, x, 0)[3] = 1;
        return img;
    };
    Image ref = render(1.0f, 0.0f), test = render(1.5f, 0.5f);
    auto e = compare_images(test, ref, "", "t.exr");
    ASSERT_EQ(e.size(), 3u);
    EXPECT_EQ(e[2].layer, kBeautyRefDirect);
    // Reference beauty: 2, 3, 4, 5 (mean 3.5); the only difference left is 0.5 at one pixel.
    EXPECT_NEAR(e[2].rmse, std::sqrt(3 * 0.25 / 12), 1e-6);
    EXPECT_NEAR(e[2].mean_ref, 3.5, 1e-6);
    EXPECT_GT(e[0].rmse, 4 * e[2].rmse);  // the plain beauty error is mostly the direct light's
    EXPECT_EQ(compare_images(ref, ref, kBeautyRefDirect, "r.exr")[0].rmse, 0.0);
    EXPECT_THROW(compare_images(flat(4, 1, 1), flat(4, 1, 1), kBeautyRefDirect, "t.exr"), InputError);
}

TEST(Compare, MismatchedImagesAreInputErrors) {
    EXPECT_THROW(compare_images(flat(10, 10, 1), flat(10, 9, 1), "", "t.exr"), InputError);
    EXPECT_THROW(compare_images(flat(10, 10, 1), flat(10, 10, 1), "ao", "t.exr"), InputError);
}

TEST(Compare, FalseColourRamp) {
    Image ref = flat(3, 1, 0), test = flat(3, 1, 0);
    test.at(test.layers[0], 1, 0)[0] = test.at(test.layers[0], 1, 0)[1] = test.at(test.layers[0], 1, 0)[2] = 0.5f;
    test.at(test.layers[0], 2, 0)[0] = test.at(test.layers[0], 2, 0)[1] = test.at(test.layers[0], 2, 0)[2] = 5.0f;
    auto rgb = error_false_colour(test, ref, "indirect", 1.0);
    EXPECT_EQ(rgb[0] + rgb[1] + rgb[2], 0);        // no error: black
    EXPECT_GT(rgb[3], 0);                          // half range: red rising
    EXPECT_EQ(rgb[6] + rgb[7] + rgb[8], 3 * 255);  // beyond range: white
}

TEST(BruteForce, CornellHasColourBleedingAndAo) {
    test::TempDir d;
    std::string out = d.file("b.exr");
    ASSERT_EQ(test::run_bounce("render " + test::cornell_scene() + " -o " + out + " --res 32x32 --spp 2 --gi brute --rays 128 -q"), 0);
    Image img = read_exr(out);
    const Layer* ind = img.find("indirect");
    ASSERT_NE(ind, nullptr);
    ASSERT_NE(img.find("ao"), nullptr);
    ASSERT_NE(img.find("bentnormal"), nullptr);
    // Ceiling (not lit directly) gets indirect light; the back wall near the red wall is
    // redder than near the green wall.
    EXPECT_GT(img.at(*ind, 16, 1)[0], 0.1f);
    const float* left = img.at(*ind, 7, 12);
    const float* right = img.at(*ind, 25, 12);
    EXPECT_GT(left[0] / left[1], 1.2f * right[0] / right[1]);
    // Beauty = direct + albedo * indirect / pi.
    const float* b = img.at(*img.find("beauty"), 16, 12);
    const float* dir = img.at(*img.find("direct"), 16, 12);
    const float* alb = img.at(*img.find("albedo"), 16, 12);
    const float* e = img.at(*ind, 16, 12);
    EXPECT_NEAR(b[1], dir[1] + alb[1] * e[1] / kPi, 1e-5f);
}

TEST(BruteForce, AoOnlyRendersAoAsBeauty) {
    test::TempDir d;
    std::string out = d.file("ao.exr");
    ASSERT_EQ(test::run_bounce("render " + test::cornell_scene() + " -o " + out + " --res 16x16 --spp 1 --ao --rays 64 -q"), 0);
    Image img = read_exr(out);
    EXPECT_EQ(img.find("direct"), nullptr);
    const Layer &ao = *img.find("ao"), &b = *img.find("beauty");
    for (int y = 2; y < 14; ++y)
        for (int x = 2; x < 14; ++x) {
            EXPECT_EQ(img.at(b, x, y)[0], img.at(ao, x, y)[0]);
            EXPECT_LE(img.at(ao, x, y)[0], 1.0f);
        }
}

TEST(BruteForce, CompareCommandReportsTheError) {
    test::TempDir d;
    std::string a = d.file("a.exr"), b = d.file("b.exr");
    std::string common = " --res 16x16 --spp 1 --gi brute -q";
    ASSERT_EQ(test::run_bounce("render " + test::cornell_scene() + " -o " + a + common + " --rays 32"), 0);
    ASSERT_EQ(test::run_bounce("render " + test::cornell_scene() + " -o " + b + common + " --rays 512"), 0);
    std::string cmd = std::string(BOUNCE_BINARY) + " compare " + a + " " + b + " --json --layer indirect > " + d.file("c.json");
    ASSERT_EQ(std::system(cmd.c_str()), 0);
    std::ifstream in(d.file("c.json"));
    auto j = nlohmann::json::parse(in);
    double rel = j["indirect"]["rel_rmse"].get<double>();
    EXPECT_GT(rel, 0.01);  // 32 rays are visibly noisy ...
    EXPECT_LT(rel, 1.0);   // ... but right on average
    EXPECT_TRUE(std::filesystem::exists(d.file("a.diff.png")));
    EXPECT_EQ(test::run_bounce("compare " + a + " " + d.file("missing.exr")), 2);
}

}  // namespace
}  // namespace bounce

namespace bounce {
namespace {

TEST(SequenceCompare, AStaticSequenceHasNoFlickerAndAKnownPerturbationItsKnownValue) {
    const auto name = [](int t) { return "frame " + std::to_string(t); };
    const auto ref = [](int) { return flat(8, 4, 2.0f); };
    SequenceError still = compare_sequences(ref, ref, 1, 5, "indirect", name);
    EXPECT_EQ(still.flicker, 0.0);
    EXPECT_EQ(still.popping, 0.0);
    EXPECT_EQ(still.mean_rel_rmse, 0.0);
    // The test alternates +c / -c about the reference: every frame difference is off by 2c, so
    // flicker = 2c / mean(ref), and each frame's error is c / mean(ref).
    const float c = 0.1f;
    const auto test = [&](int t) { return flat(8, 4, 2.0f + (t % 2 ? c : -c)); };
    SequenceError e = compare_sequences(test, ref, 1, 5, "indirect", name);
    EXPECT_NEAR(e.flicker, 2 * c / 2.0, 1e-6);
    EXPECT_NEAR(e.popping, 2 * c / 2.0, 1e-6);
    EXPECT_NEAR(e.mean_rel_rmse, c / 2.0, 1e-6);
    // A test that lags the reference by a constant offset changes as the reference does: no flicker.
    const auto moving = [](int t) { return flat(8, 4, 1.0f + 0.1f * static_cast<float>(t)); };
    const auto offset = [](int t) { return flat(8, 4, 1.05f + 0.1f * static_cast<float>(t)); };
    EXPECT_NEAR(compare_sequences(offset, moving, 1, 5, "indirect", name).flicker, 0.0, 1e-6);
}

TEST(SequenceCompare, TheStripIsAPngThatOverwritesNoFrameItReads) {
    test::TempDir d;
    ASSERT_EQ(test::run_bounce("render " + test::cornell_scene() + " -o " + d.file("f.####.exr") +
                               " --frames 1-2 --res 8x8 --spp 1 --gi brute --rays 8 -q"),
              0);
    for (int t : {1, 2}) std::filesystem::copy_file(d.file(fmt::format("f.{:04d}.exr", t)), d.file(fmt::format("r.{:04d}.png", t)));
    const std::string cmd = "compare --sequence " + d.file("f.####.exr") + " " + d.file("r.####.png") + " --frames 1-2 --strip ";
    const std::string frame = test::bytes_of(d.file("f.0001.exr")), ref = test::bytes_of(d.file("r.0002.png"));
    test::expect_refused(cmd + d.file("f.0001.exr"), {"--strip", "the strip is a PNG file (.png)"});
    test::expect_refused(cmd + d.file("r.0002.png"), {"r.0002.png", "output names an input"});
    EXPECT_EQ(test::bytes_of(d.file("f.0001.exr")), frame);
    EXPECT_EQ(test::bytes_of(d.file("r.0002.png")), ref);
    EXPECT_EQ(test::run_bounce(cmd + d.file("strip.png")), 0);
    EXPECT_GT(test::bytes_of(d.file("strip.png")).size(), 100u);
}

}  // namespace
}  // namespace bounce
