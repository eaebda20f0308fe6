// The lighter's workflow as library calls: crops re-shaded and re-gathered from a deep file and
// a cache, caches that know their settings, previews lit like the final image, cancellation.
#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "bounce/cache/cache_file.h"
#include "bounce/core/error.h"
#include "bounce/render/frame.h"
#include "bounce/render/render.h"
#include "bounce/scene/scene_load.h"
#include "test_util.h"

namespace bounce {
namespace {

Scene cornell(std::vector<Override> extra = {}) {
    std::vector<Override> o = {"camera.resolution=[64,64]", "render.spp=2", "render.gi=\"cache\"", "render.rays=64",
                               "render.light_samples=4"};
    o.insert(o.end(), extra.begin(), extra.end());
    return load_scene(test::cornell_scene(), o);
}

/// Renders the full frame once: its deep file and cache file, and its image.
struct FullFrame {
    test::TempDir dir;
    RenderResult result;
    std::string deep, cache;
    FullFrame() : deep(dir.file("f.deep.exr")), cache(dir.file("f.bic")) {
        RenderRequest req;
        req.deep_out = deep;
        Stats s;
        result = render(cornell(), req, s, nullptr);
        write_cache_file(cache, result.cache->to_file(result.cache_info));
    }
    /// A request that starts from this frame's deep file and cache.
    RenderRequest reuse() const {
        RenderRequest req;
        req.deep_in = deep;
        req.cache_in = cache;
        return req;
    }
};

/// Layer `name` of `full` at window pixel (x, y) of `crop` equals `crop`'s own.
void expect_window_equal(const Image& full, const Image& crop, const std::string& name) {
    const Layer& fl = *full.find(name);
    const Layer& cl = *crop.find(name);
    const size_t nc = fl.channels.size();
    for (int y = 0; y < crop.height; ++y)
        for (int x = 0; x < crop.width; ++x)
            for (size_t c = 0; c < nc; ++c)
                ASSERT_EQ(cl.data[(static_cast<size_t>(y) * crop.width + x) * nc + c],
                          fl.data[(static_cast<size_t>(y + crop.y0) * full.width + x + crop.x0) * nc + c])
                    << name << " at " << x + crop.x0 << "," << y + crop.y0;
}

TEST(SubViewport, CropReshadeFromDeepAndCacheEqualsTheFullRender) {
    FullFrame f;
    RenderRequest req = f.reuse();
    Stats s;
    RenderResult crop = render(cornell({"render.crop=[10,34,20,40]"}), req, s, nullptr);
    EXPECT_EQ(crop.image.width, 24);
    EXPECT_EQ(crop.image.height, 20);
    EXPECT_EQ(crop.deep.pixel_count(), 24u * 20u);
    EXPECT_EQ(crop.records_new, 0u);
    EXPECT_EQ(s.total().gather_rays, 0u);
    for (const char* layer : {"beauty", "indirect", "ao", "direct"}) expect_window_equal(f.result.image, crop.image, layer);
}

TEST(SubViewport, ADeepFileOfAWindowRendersThatWindowWithoutACrop) {
    test::TempDir d;
    RenderRequest req;
    req.deep_out = d.file("w.deep.exr");
    Stats s;
    RenderResult first = render(cornell({"render.crop=[4,20,8,30]", "render.gi=\"none\""}), req, s, nullptr);
    RenderRequest again;
    again.deep_in = d.file("w.deep.exr");
    RenderResult second = render(cornell({"render.gi=\"none\""}), again, s, nullptr);
    EXPECT_EQ(second.image.x0, 4);
    EXPECT_EQ(second.image.width, 16);
    EXPECT_EQ(second.image.height, 22);
    EXPECT_TRUE(second.image.find("beauty")->data == first.image.find("beauty")->data);
    // A crop outside the file's window is refused, naming the window it has.
    EXPECT_THROW(render(cornell({"render.gi=\"none\"", "render.crop=[0,10,0,10]"}), again, s, nullptr), InputError);
}

TEST(SubViewport, CropRegatherKeepsTheRestAndAFullReshadeHasNoMisses) {
    FullFrame f;
    RenderRequest req = f.reuse();
    req.kind = FrameKind::Regather;
    Stats s;
    RenderResult crop = render(cornell({"render.crop=[16,48,16,48]"}), req, s, nullptr);
    EXPECT_GT(crop.records_new, 0u);
    EXPECT_LT(crop.records_loaded, f.result.cache->size());  // the crop's records were dropped
    test::TempDir d;
    write_cache_file(d.file("g.bic"), crop.cache->to_file(crop.cache_info));
    RenderRequest full;
    full.deep_in = f.deep;
    full.cache_in = d.file("g.bic");
    Stats s2;
    RenderResult all = render(cornell(), full, s2, nullptr);
    EXPECT_EQ(all.records_new, 0u);
    EXPECT_EQ(s2.to_json()["shading_misses"].get<double>(), 0.0);
}

TEST(SubViewport, BaseImageFillsThePixelsOutsideTheCrop) {
    FullFrame f;
    test::TempDir d;
    write_exr(d.file("base.exr"), f.result.image);
    RenderRequest req = f.reuse();
    Stats s;
    RenderResult crop = render(cornell({"render.crop=[8,20,8,30]", "render.light_samples=16"}), req, s, nullptr);
    Image whole = paste_over(read_exr(d.file("base.exr")), crop.image, "base.exr");
    EXPECT_EQ(whole.width, 64);
    const Layer& b = *whole.find("beauty");
    const Layer& fb = *f.result.image.find("beauty");
    EXPECT_EQ(whole.at(const_cast<Layer&>(b), 40, 40)[0], f.result.image.find("beauty")->data[(40 * 64 + 40) * 4]);
    // Inside the crop the new light samples show.
    EXPECT_NE(b.data[(10 * 64 + 10) * 4], fb.data[(10 * 64 + 10) * 4]);
    Image small;
    small.full_width = small.full_height = small.width = small.height = 32;
    EXPECT_THROW(paste_over(small, crop.image, "small.exr"), InputError);
}

TEST(CacheIdentity, OtherRecordSettingsAreRefusedNamingEachKeyUnlessReusedOrRegathered) {
    FullFrame f;
    RenderRequest req = f.reuse();
    Stats s;
    try {
        render(cornell({"render.min_spacing=1", "render.rays=100"}), req, s, nullptr);
        FAIL();
    } catch (const InputError& e) {
        std::string m = e.what();
        EXPECT_NE(m.find("render.min_spacing: 2.0 -> 1.0"), std::string::npos) << m;
        EXPECT_NE(m.find("render.rays: 64 -> 100"), std::string::npos) << m;
    }
    // Shading-only settings stay free.
    EXPECT_NO_THROW(render(cornell({"render.shading_reach=2", "render.light_per_channel=true"}), req, s, nullptr));
    req.cache_reuse = CacheReuse::Any;
    Stats s2;
    RenderResult r = render(cornell({"render.quality=3"}), req, s2, nullptr);
    EXPECT_EQ(s2.to_json()["cache_reused_with_other_settings"].size(), 1u);
    EXPECT_GT(r.records_new, 0u);  // records reach less: gathers where the old ones now miss
    req.cache_reuse = CacheReuse::Strict;
    req.kind = FrameKind::Regather;
    EXPECT_NO_THROW(render(cornell({"render.min_spacing=1"}), req, s, nullptr));
}

TEST(Preview, TheLastPreviewFrameIsTheFinalImageOnABumpedGlossyScene) {
    Scene s = load_scene(test::source_dir() + "/scenes/cornell/glossy-bump.json",
                         {"camera.resolution=[40,40]", "render.spp=1", "render.rays=64", "render.preview=true"});
    ASSERT_EQ(s.render.indirect.gi, GiMode::Cache);
    std::vector<Image> frames;
    RenderRequest req;
    req.preview = [&](const Image& img) { frames.push_back(img); };
    Stats stats;
    RenderResult r = render(s, req, stats, nullptr);
    ASSERT_FALSE(frames.empty());
    for (const char* layer : {"beauty", "direct", "indirect"})
        EXPECT_TRUE(frames.back().find(layer)->data == r.image.find(layer)->data) << layer;
}

TEST(Cancel, ATokenStopsALongGatherPromptly) {
    Scene s = cornell({"camera.resolution=[256,256]", "render.gi=\"brute\"", "render.rays=4096", "render.threads=2"});
    CancelToken token;
    RenderRequest req;
    req.cancel = &token;
    Stats stats;
    std::chrono::steady_clock::time_point cancelled_at;
    std::thread canceller([&] {
        std::this_thread::sleep_for(std::chrono::milliseconds(300));
        cancelled_at = std::chrono::steady_clock::now();
        token.cancel();
    });
    EXPECT_THROW(render(s, req, stats, nullptr), Cancelled);
    auto waited = std::chrono::steady_clock::now() - cancelled_at;
    canceller.join();
    // The whole render takes minutes; one gather (4096 rays) takes about a millisecond.
    EXPECT_LT(std::chrono::duration<double>(waited).count(), 1.0);
}

TEST(Frames, SequencesTakeThePreviousFramesCacheAndOutputsAreChecked) {
    FrameFiles p;
    p.scene = test::cornell_scene();
    p.output = "/tmp/x.####.exr";
    p.cache_in = "start.bic";
    p.cache_out = "/tmp/c.####.bic";
    EXPECT_EQ(sequence_frame(p, 3, 3).cache_in, "start.bic");
    EXPECT_EQ(sequence_frame(p, 3, 5).cache_in, "/tmp/c.0004.bic");
    EXPECT_EQ(sequence_frame(p, 3, 5).output, "/tmp/x.0005.exr");
    EXPECT_EQ(parse_frame_range("1-24", "--frames"), std::make_pair(1, 24));
    EXPECT_THROW(parse_frame_range("5-2", "--frames"), InputError);
    FrameFiles bad;
    bad.scene = test::cornell_scene();
    const Scene scene = load_scene(bad.scene);
    test::TempDir d;
    bad.output = d.file("new.exr");
    EXPECT_NO_THROW(bad.check(scene));  // a new name in a folder that takes files
    for (const std::string& out : {std::string("/dev/null"), test::cornell_scene(), std::string("/proc/x.exr"),
                                   d.write("c.bic", "x") + "/x.exr", d.file("missing/x.exr")}) {
        bad.output = out;
        EXPECT_THROW(bad.check(scene), InputError) << out;
    }
}

}  // namespace
}  // namespace bounce
