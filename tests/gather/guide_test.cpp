// Issue 47, route 3: gathers guided by a pilot (gather/guide.h). The split of rays over the 32
// bins is exact arithmetic, every ray lies in its bin with its share of the hemisphere, a
// constant environment stays constant under any guide, the guided estimator stays unbiased on
// the Cornell box over many seeds with a good guide and a perverse one, and guided brute force
// needs fewer rays than plain for the same error there.
#include <gtest/gtest.h>

#include <cmath>
#include <numeric>

#include "bounce/cache/control_variate.h"
#include "bounce/cache/passes.h"
#include "bounce/gather/guide.h"
#include "bounce/render/render.h"
#include "test_util.h"

namespace bounce {
namespace {

DirectionGuide one_bin(size_t b, float value = 1) {
    DirectionGuide g;
    g.spread[b] = value;
    return g;
}

TEST(Guide, AllocationGivesEveryBinARayAndTheRestByTheMixture) {
    // Even: no spread anywhere, or a share of 0.
    for (const auto& a : {guided_allocation(DirectionGuide{}, 256, 0.8f), guided_allocation(one_bin(5), 256, 0.0f)})
        for (int n : a) EXPECT_EQ(n, 8);
    // Everything in bin 5 with share 0.5: 1 + 224 x (0.5/32 + 0.5) = 116.5 there, 1 + 3.5 elsewhere.
    const auto a = guided_allocation(one_bin(5), 256, 0.5f);
    EXPECT_EQ(std::accumulate(a.begin(), a.end(), 0), 256);
    EXPECT_EQ(a[5], 117);  // remainders all 0.5: the 16 left over go to bins 0-15
    for (size_t b = 0; b < a.size(); ++b)
        if (b != 5) {
            EXPECT_TRUE(a[b] == 4 || a[b] == 5) << b;
        }
    // NaN, infinite and negative spreads count as none; fewer rays than bins: no guide, one each.
    DirectionGuide hostile = one_bin(3);
    hostile.spread[4] = NAN, hostile.spread[6] = INFINITY, hostile.spread[7] = -1;
    const auto h = guided_allocation(hostile, 64, 1.0f);
    EXPECT_EQ(h[3], 33);
    EXPECT_EQ(h[4], 1);
    EXPECT_EQ(h[6], 1);
    const auto few = guided_allocation(one_bin(3), 8, 0.9f);
    EXPECT_EQ(std::accumulate(few.begin(), few.end(), 0), 8);
    EXPECT_EQ(*std::max_element(few.begin(), few.end()), 1);
}

TEST(Guide, EveryRayLiesInItsBinWithItsShareOfTheHemisphere) {
    DirectionGuide g;
    for (size_t b = 0; b < g.spread.size(); ++b) g.spread[b] = static_cast<float>(b % 5);
    for (int rays : {32, 100, 512, 1031}) {
        const auto alloc = guided_allocation(g, rays, 0.7f);
        GuidedRays out;
        guided_rays(alloc, RandomStream(3, static_cast<uint64_t>(rays)), out);
        ASSERT_EQ(out.local.size(), static_cast<size_t>(rays));
        std::array<double, kReachBins> share{};
        size_t i = 0;
        for (int b = 0; b < kReachBins; ++b)
            for (int k = 0; k < alloc[static_cast<size_t>(b)]; ++k, ++i) {
                EXPECT_EQ(direction_bin(out.local[i]), b) << "ray " << i;
                EXPECT_NEAR(length(out.local[i]), 1.0f, 1e-5f);
                share[static_cast<size_t>(b)] += out.weight[i];
            }
        for (double s : share) EXPECT_NEAR(s, 1.0 / kReachBins, 1e-6);  // each bin's measure, whatever its rays
    }
}

TEST(Guide, AConstantEnvironmentStaysConstantUnderAnyGuide) {
    // Inside a uniformly lit sphere every wall's radiance is rho I / pi (radiosity textures):
    // E = rho I / R^2 at any point, guided or not (gather_test's closed form).
    const float rho = 0.6f, I = 2.0f;
    nlohmann::json j = test::base_scene();
    j["materials"] = {{"m", {{"color", rho}}}};
    j["objects"] = {{{"type", "sphere"}, {"radius", 1.0}, {"subdivisions", 5}, {"fine_subdivisions", 0}, {"material", "m"}}};
    j["lights"] = {{{"type", "point"}, {"position", {0, 0, 0}}, {"color", I}}};
    const Scene scene = test::scene_from(j);
    const SceneAccel accel(scene, scene.render.lighting);
    const Materials materials(scene);
    const DirectLighting lighting(scene, accel, scene.render.lighting);
    Stats stats;
    RadiositySettings rs;
    rs.texel = 0.02f;
    const RadiosityTextures textures = RadiosityTextures::bake(scene, materials, lighting, rs, stats, nullptr);
    GatherSettings gs;
    gs.rays = 64, gs.record_terms = false, gs.guided = 0.9f;
    const Gatherer gatherer(scene, accel, materials, lighting, &textures, gs);
    const SurfacePoint sp = surface_point(scene.objects[0].coarse, 777, 0.3f, 0.3f);
    for (size_t b : {0u, 17u, 31u}) {
        const GatherResult r = gatherer.gather_guided(sp.p, -normalize(sp.p), RandomStream(1, b), one_bin(b), stats.local());
        EXPECT_NEAR(r.irradiance.x, rho * I, 0.01f * rho * I) << "guide in bin " << b;
        EXPECT_EQ(r.ao, 0.0f);
        EXPECT_EQ(r.rays, gatherer.grid().rays());
    }
}

struct Cornell {
    explicit Cornell(const char* resolution = "camera.resolution=[32,24]")
        : scene(load_scene(test::cornell_scene(), {resolution, "render.spp=1", "render.gi=\"brute\""})) {}
    Scene scene;
    Stats stats;
    SceneAccel accel{scene, scene.render.lighting};
    DeepBuffer deep = render_visibility(scene, accel, scene.render.visibility, stats, nullptr);
    Materials materials{scene};
    DirectLighting lighting{scene, accel, scene.render.lighting};
    Gatherer gatherer(int rays, float guided) const {
        GatherSettings gs = test::still_plan(scene).gather;
        gs.rays = rays, gs.record_terms = false, gs.guided = guided;
        return Gatherer(scene, accel, materials, lighting, nullptr, gs);
    }
};

/// Mean and standard deviation of `estimate(seed)` over `seeds` seeds.
template <class Fn>
std::pair<double, double> over_seeds(int seeds, Fn&& estimate) {
    double sum = 0, sq = 0;
    for (int s = 0; s < seeds; ++s) {
        const double v = estimate(static_cast<uint64_t>(s));
        sum += v, sq += v * v;
    }
    const double mean = sum / seeds;
    return {mean, std::sqrt(std::max(0.0, sq / seeds - mean * mean))};
}

TEST(Guide, TheGuidedEstimatorStaysUnbiasedWhateverTheGuideAndAGoodGuideLowersItsVariance) {
    // At fragments of the Cornell box, 64 guided rays averaged over 300 seeds against a
    // 16 384-ray gather: within 4 standard errors, guided by a pilot at the fragment and by a
    // guide that puts nearly every ray in one bin. The pilot's guide lowers the variance of
    // the 64-ray gather summed over the fragments.
    Cornell c;
    const Gatherer plain = c.gatherer(64, 0), guided = c.gatherer(64, 0.5f), big = c.gatherer(16384, 0);
    const Gatherer pilots = c.gatherer(1024, 0);
    const int seeds = 300;
    int checked = 0;
    double var_plain = 0, var_guided = 0;
    for (size_t f = 0; f < c.deep.fragments.size(); f += c.deep.fragments.size() / 5) {
        const Fragment& frag = c.deep.fragments[f];
        Counters& counters = c.stats.local();
        const double truth = big.gather(frag.p, frag.n, RandomStream(99, f, 1), counters).irradiance.y;
        const DirectionGuide pilot = pilots.pilot(frag.p, frag.n, RandomStream(98, f, 1), counters);
        const std::array<DirectionGuide, 2> guides{pilot, one_bin(20)};
        for (size_t g = 0; g < guides.size(); ++g) {
            const DirectionGuide& guide = guides[g];
            const auto [mean, sd] = over_seeds(seeds, [&](uint64_t s) {
                return guided.gather_guided(frag.p, frag.n, RandomStream(7, f, s), guide, counters).irradiance.y;
            });
            EXPECT_NEAR(mean, truth, 4 * sd / std::sqrt(seeds) + 1e-3 * truth) << "fragment " << f;
            if (g == 0) var_guided += sd * sd;
            ++checked;
        }
        const auto sd_plain = over_seeds(seeds, [&](uint64_t s) {
                                  return plain.gather(frag.p, frag.n, RandomStream(7, f, s), counters).irradiance.y;
                              }).second;
        var_plain += sd_plain * sd_plain;
    }
    EXPECT_GE(checked, 10);
    EXPECT_LT(var_guided, 0.8 * var_plain) << var_plain << " -> " << var_guided;  // 2.3x lower when written
}

TEST(Guide, GuidedBruteForceIsIndependentOfTheWindow) {
    // A window whose edges follow the 8-pixel grid finds the same pilots: the same bits.
    Cornell c;
    const Gatherer guided = c.gatherer(64, 0.5f);
    const std::vector<Indirect> whole = gather_every_fragment(c.scene, c.deep, guided, c.stats, nullptr);
    const DeepBuffer window = sub_window(c.deep, {8, 24, 8, 24});
    const std::vector<Indirect> part = gather_every_fragment(c.scene, window, guided, c.stats, nullptr);
    size_t i = 0, guided_differs = 0;
    const std::vector<Indirect> plain = gather_every_fragment(c.scene, c.deep, c.gatherer(64, 0), c.stats, nullptr);
    for (int y = 0; y < window.height; ++y)
        for (int x = 0; x < window.width; ++x)
            for (size_t k = 0; k < window.pixel(x, y).size(); ++k, ++i) {
                const size_t at =
                    c.deep.offsets[static_cast<size_t>(y + 8) * static_cast<size_t>(c.deep.width) + static_cast<size_t>(x + 8)] + k;
                ASSERT_EQ(part[i].irradiance, whole[at].irradiance) << x << "," << y;
                guided_differs += !(whole[at].irradiance == plain[at].irradiance);
            }
    EXPECT_GT(guided_differs, i / 2);  // the guide was used
}

TEST(Guide, RecordsKeepTheirGuideAndRefinementGathersFollowIt) {
    // With render.guided every record keeps how its cells varied per bin; a refinement gather
    // (no gradients) is guided by the records that cover its fragment: the same fragments are
    // refined, with other (guided) values.
    Cornell c;
    c.scene.render.indirect.gi = GiMode::Cache;
    GatherSettings gs = test::still_plan(c.scene).gather;
    gs.guided = 0.5f;
    std::array<IrradianceCache, 2> caches{IrradianceCache(c.scene.bounds(), c.scene.render.cache, false),
                                          IrradianceCache(c.scene.bounds(), c.scene.render.cache, false)};
    std::array<size_t, 2> refined{};
    for (size_t i = 0; i < 2; ++i) {
        gathering_pass(c.scene, c.deep, Gatherer(c.scene, c.accel, c.materials, c.lighting, nullptr, gs), caches[i], c.stats, nullptr);
        GatherSettings own = gs;
        own.record_terms = false, own.guided = i == 0 ? 0.5f : 0.0f;
        const Gatherer refiner(c.scene, c.accel, c.materials, c.lighting, nullptr, own);
        refined[i] = refinement_pass(c.scene, c.deep, refiner, caches[i], c.stats, nullptr, {});
    }
    size_t guides = 0;
    for (size_t r = 0; r < caches[0].size(); ++r) guides += caches[0].record(r).guide != nullptr;
    EXPECT_EQ(guides, caches[0].size());
    const Fragment& f = c.deep.fragments[c.deep.fragments.size() / 2];
    const auto guide = guide_from_records(caches[0], f.p, f.n, f.n);
    ASSERT_TRUE(guide.has_value());
    EXPECT_GT(std::accumulate(guide->spread.begin(), guide->spread.end(), 0.0f), 0.0f);
    ASSERT_GT(refined[0], 0u);
    EXPECT_EQ(refined[0], refined[1]);
    size_t differ = 0;
    for (size_t r = 0; r < caches[0].fragment_record_count(); ++r)
        differ += !(caches[0].fragment_record_at(r).E == caches[1].fragment_record_at(r).E);
    EXPECT_GT(differ, refined[0] / 2);
}

}  // namespace
}  // namespace bounce
