// Per-fragment refinement: fragments whose records disagree get gathers of their own.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <utility>

#include "bounce/cache/cache_file.h"
#include "bounce/cache/irradiance_cache.h"
#include "bounce/cache/sites.h"
#include "bounce/render/render.h"
#include "bounce/scene/scene_load.h"
#include "test_util.h"

namespace bounce {
namespace {

Scene cornell(std::vector<Override> extra) {
    std::vector<Override> o = {"camera.resolution=[40,40]", "render.spp=1", "render.rays=64", "render.light_samples=4"};
    o.insert(o.end(), extra.begin(), extra.end());
    return load_scene(test::cornell_scene(), o);
}

/// The lookup midway between two records of values 1 and 3 (equal weights, no gradients), each
/// gathered with relative standard error `noise`, in a cache of `refine_noise`.
Interpolated between_two_records(float noise, float refine_noise) {
    CacheSettings cs;
    cs.refine_noise = refine_noise;
    IrradianceCache cache(Bounds{Vec3(-10), Vec3(10)}, cs, false);
    cache.set_luminance_floor(1e-6f);
    for (auto [x, e] : {std::pair{-0.5f, 1.0f}, std::pair{0.5f, 3.0f}}) {
        Record r;
        r.p = {x, 0, 0}, r.n = {0, 0, 1}, r.E = Color(e), r.noise = noise;
        r.radius = r.raw_radius = 10, r.footprint = 1, r.support = 20;
        cache.insert_loaded(r);
    }
    return cache.lookup({0, 0, 0}, {0, 0, 1});
}

TEST(Refine, SpreadIsTheWeightedRelativeDeviationOfTheRecords) {
    const Interpolated in = between_two_records(0, CacheSettings{}.refine_noise);
    // Equal weights at the midpoint; gradients are zero: values 1 and 3, mean 2, deviation 1.
    ASSERT_EQ(in.records, 2);
    EXPECT_NEAR(in.spread, 0.5f, 1e-5f);
    EXPECT_NEAR(luminance(in.E), 2.0f, 1e-5f);
}

TEST(Refine, TheSpreadLeavesOutWhatTheRecordsOwnNoiseExplains) {
    // Values 1 and 3 at equal weights (mean 2, weighted variance 1), each record's gather with
    // relative standard error s. Independent estimates of one value would spread by
    // sum(w (s l)^2)/W (1 - sum(w^2)/W^2) = (s^2 + 9 s^2)/2 x 1/2 = 2.5 s^2, and a fragment's own
    // gather (at the records' rays) would bring sum(w (s l)^2)/W = 5 s^2 where the interpolation
    // carries sum(w^2 (s l)^2)/W^2 = 2.5 s^2: 2.5 s^2 more. Refinement judges the variance beyond
    // refine_noise times both, 5 s^2.
    const auto spread = [](float noise, float refine_noise) {
        const Interpolated in = between_two_records(noise, refine_noise);
        EXPECT_NEAR(luminance(in.E), 2.0f, 1e-5f);  // the value itself is untouched
        return in.spread;
    };
    EXPECT_NEAR(spread(0.2f, 0), 0.5f, 1e-5f);                     // the raw spread
    EXPECT_NEAR(spread(0.2f, 1), std::sqrt(1 - 0.2f) / 2, 1e-5f);  // 1 - 5 x 0.04
    EXPECT_NEAR(spread(0.2f, 2), std::sqrt(1 - 0.4f) / 2, 1e-5f);  // the default
    EXPECT_NEAR(spread(0, 2), 0.5f, 1e-5f);                        // noiseless records
    EXPECT_EQ(spread(0.5f, 2), 0.0f);                              // all of it noise: 2.5 > 1
}

// Issue 65 (ic-algorithms.md 2.4): a record whose neighbour clamp lowers its radius below the
// minimum spacing is kept at that spacing, further than its gradient holds: its translational
// gradients (irradiance, AO) are scaled by raw / R_min, as a short raw radius is at creation.
TEST(Refine, ANeighbourClampBelowTheMinimumSpacingCapsTheGradient) {
    CacheSettings cs;
    cs.min_spacing = 2;  // x a footprint of 1: R_min = 2
    IrradianceCache cache(Bounds{Vec3(-10), Vec3(10)}, cs, false);
    Record near;
    near.p = {0, 0, 0}, near.n = {0, 0, 1}, near.E = Color(1);
    near.raw_radius = 1, near.radius = 2, near.footprint = 1;
    cache.insert_loaded(near);
    Record r;
    r.p = {0.2f, 0, 0}, r.n = {0, 0, 1}, r.E = Color(1), r.footprint = 1;
    r.raw_radius = 10, r.radius = 10;
    r.grad_t = {Vec3(1, 0, 0), Vec3(0, 2, 0), Vec3(0, 0, 3)};
    r.ao_grad_t = Vec3(4, 0, 0);
    cache.clamp_to_neighbours(r);
    // 1 + 0.2 = 1.2 < R_min: kept at 2, the gradients at 1.2 / 2 of what they were.
    EXPECT_NEAR(r.raw_radius, 1.2f, 1e-6f);
    EXPECT_EQ(r.radius, 2.0f);
    EXPECT_NEAR(r.grad_t[0].x, 0.6f, 1e-6f);
    EXPECT_NEAR(r.grad_t[1].y, 1.2f, 1e-6f);
    EXPECT_NEAR(r.grad_t[2].z, 1.8f, 1e-6f);
    EXPECT_NEAR(r.ao_grad_t.x, 2.4f, 1e-6f);
    // A clamp that stays above R_min changes no gradient.
    Record far = r;
    far.p = {1.5f, 0, 0}, far.raw_radius = 10, far.grad_t = {Vec3(1, 0, 0), Vec3(0), Vec3(0)};
    cache.clamp_to_neighbours(far);
    EXPECT_NEAR(far.raw_radius, 2.5f, 1e-5f);  // clamped, not below R_min
    EXPECT_EQ(far.grad_t[0].x, 1.0f);
}

TEST(Refine, ARecordKeepsItsGathersNoiseEstimate) {
    IrradianceCache cache(Bounds{Vec3(-10), Vec3(10)}, CacheSettings{}, false);
    GatherResult g;
    g.irradiance = Color(2);
    g.rel_stderr = 0.125f;
    Record r;
    cache.set_values(r, g);
    EXPECT_EQ(r.noise, 0.125f);
    // Near darkness the estimate divides by almost nothing: capped, so a cache file keeps it.
    for (float wild : {1e30f, INFINITY, NAN}) {
        g.rel_stderr = wild;
        cache.set_values(r, g);
        EXPECT_EQ(r.noise, 1e3f) << wild;
    }
}

TEST(Refine, RefinedFragmentsCarryTheirOwnGatherExactly) {
    Stats s1, s2;
    RenderResult brute = render(cornell({"render.gi=\"brute\""}), {}, s1, nullptr);
    // A threshold this low, on the raw spread, refines every fragment whose records differ at all.
    RenderResult refined = render(cornell({"render.gi=\"cache\"", "render.refine=1e-9", "render.refine_noise=0"}), {}, s2, nullptr);
    const Layer* mask = refined.image.find("refined");
    ASSERT_NE(mask, nullptr);
    const Layer& a = *brute.image.find("indirect");
    const Layer& b = *refined.image.find("indirect");
    size_t same = 0, full = 0;
    for (int i = 0; i < 40 * 40; ++i) {
        if (mask->data[static_cast<size_t>(i)] != 1.0f || refined.deep.pixel(i % 40, i / 40).size() != 1) continue;
        ++full;
        same += a.data[3 * static_cast<size_t>(i)] == b.data[3 * static_cast<size_t>(i)];
    }
    EXPECT_GT(full, 800u);
    EXPECT_EQ(same, full);
    EXPECT_GT(s2.to_json()["refined_fragments"].get<double>(), 800.0);
    EXPECT_EQ(s2.to_json()["shading_misses"].get<double>(), 0.0);
}

TEST(Refine, OffMakesNoFragmentRecordsAndTheDecisionDoesNotDependOnThreads) {
    Stats s1, s2, s3;
    RenderResult off = render(cornell({"render.gi=\"cache\"", "render.refine=0"}), {}, s1, nullptr);
    EXPECT_EQ(off.image.find("refined"), nullptr);
    EXPECT_EQ(off.cache->fragment_record_count(), 0u);
    RenderResult one = render(cornell({"render.gi=\"cache\"", "render.refine=0.05", "render.threads=1"}), {}, s2, nullptr);
    RenderResult two = render(cornell({"render.gi=\"cache\"", "render.refine=0.05", "render.threads=2"}), {}, s3, nullptr);
    ASSERT_NE(one.image.find("refined"), nullptr);
    EXPECT_TRUE(one.image.find("refined")->data == two.image.find("refined")->data);
    EXPECT_TRUE(one.image.find("indirect")->data == two.image.find("indirect")->data);
    const double n = s2.to_json()["refined_fragments"].get<double>();
    EXPECT_GT(n, 0.0);
    EXPECT_LT(n, 40.0 * 40.0);
    EXPECT_EQ(one.cache->fragment_record_count(), static_cast<size_t>(n));
    // Unrefined fragments see only the shared records: the same light as without refinement.
    const Layer &mask = *one.image.find("refined"), &a = *one.image.find("indirect"), &b = *off.image.find("indirect");
    size_t differ = 0;
    for (size_t i = 0; i < mask.data.size(); ++i)
        if (mask.data[i] == 0.0f) differ += a.data[3 * i] != b.data[3 * i];
    EXPECT_EQ(differ, 0u);
}

TEST(Refine, RefinedFragmentsAreStoredInTheCacheAndAReshadeGathersNothing) {
    test::TempDir d;
    Stats s1, s2;
    const Scene scene = cornell({"render.gi=\"cache\"", "render.refine=0.05"});
    RenderResult first = render(scene, {}, s1, nullptr);
    write_cache_file(d.file("c.bic"), first.cache->to_file(first.cache_info));
    const double made = s1.to_json()["refined_fragments"].get<double>();
    ASSERT_GT(made, 0.0);
    EXPECT_EQ(read_cache_file(d.file("c.bic")).fragment_records.size(), static_cast<size_t>(made));
    RenderRequest again;
    again.cache_in = d.file("c.bic");
    RenderResult second = render(scene, again, s2, nullptr);
    EXPECT_EQ(s2.total().gather_rays, 0u);
    EXPECT_EQ(s2.to_json()["refined_fragments"].get<double>(), 0.0);
    EXPECT_EQ(s2.to_json()["fragment_records_used"].get<double>(), made);
    EXPECT_TRUE(first.image.find("indirect")->data == second.image.find("indirect")->data);
    EXPECT_TRUE(first.image.find("refined")->data == second.image.find("refined")->data);
}

TEST(Refine, InsideTheBandAFragmentBlendsItsGatherWithTheInterpolationInProportion) {
    // The same records three ways: interpolated only, refined with a hard switch, refined with
    // refine_band 3. A refined fragment whose records spread by s_r shows the share
    // (s_r - refine) / (2 refine), at most 1, of its own gather (the hard switch's value) and
    // the rest of the interpolation.
    Stats s0, s1, s2;
    RenderResult interpolated = render(cornell({"render.gi=\"cache\"", "render.refine=0"}), {}, s0, nullptr);
    RenderResult hard = render(cornell({"render.gi=\"cache\"", "render.refine=0.05", "render.refine_noise=0"}), {}, s1, nullptr);
    const Scene scene = cornell({"render.gi=\"cache\"", "render.refine=0.05", "render.refine_band=3", "render.refine_noise=0"});
    RenderResult band = render(scene, {}, s2, nullptr);
    ASSERT_EQ(interpolated.cache->size(), band.cache->size());
    ASSERT_EQ(s1.to_json()["refined_fragments"], s2.to_json()["refined_fragments"]);  // the same gathers
    const Layer &i0 = *interpolated.image.find("indirect"), &i1 = *hard.image.find("indirect"), &i2 = *band.image.find("indirect");
    const Layer& mask = *band.image.find("refined");
    int partial = 0, whole = 0;
    for (int y = 0; y < 40; ++y)
        for (int x = 0; x < 40; ++x) {
            const auto i = static_cast<size_t>(y * 40 + x);
            if (mask.data[i] != 1.0f || band.deep.pixel(x, y).size() != 1) continue;
            const Fragment& f = band.deep.pixel(x, y)[0];
            const Interpolated in = interpolate_at(*band.cache, f, record_site(scene, f, band.cache->settings()));
            const float share = std::clamp((in.spread - 0.05f) / 0.1f, 0.0f, 1.0f);
            partial += share < 1, whole += share == 1;
            for (size_t c = 0; c < 3; ++c) {
                const float want = share * i1.data[3 * i + c] + (1 - share) * i0.data[3 * i + c];
                ASSERT_NEAR(i2.data[3 * i + c], want, 1e-4f * std::max(1.0f, std::abs(want))) << x << "," << y << " share " << share;
            }
        }
    EXPECT_GT(partial, 20);
    EXPECT_GT(whole, 20);
}

TEST(Refine, AFragmentRecordServesOnlyItsKeyAtItsExactPoint) {
    IrradianceCache cache(Bounds{Vec3(-10), Vec3(10)}, CacheSettings{}, false);
    Record r;
    r.p = {1, 2, 3};
    r.E = Color(5);
    r.key = 77;
    cache.insert_fragment_record(r);
    r.E = Color(9);
    cache.insert_fragment_record(r);  // the same key again: the first stays
    ASSERT_NE(cache.fragment_record(77, {1, 2, 3}), nullptr);
    EXPECT_EQ(cache.fragment_record(77, {1, 2, 3})->E, Color(5));
    EXPECT_EQ(cache.fragment_record(77, {1, 2, std::nextafter(3.0f, 4.0f)}), nullptr);  // another deep buffer's fragment
    EXPECT_EQ(cache.fragment_record(78, {1, 2, 3}), nullptr);
    EXPECT_EQ(cache.size(), 0u);  // no lookup can find it
    EXPECT_EQ(cache.lookup({1, 2, 3}, {0, 0, 1}).weight, 0.0f);
}

}  // namespace
}  // namespace bounce
