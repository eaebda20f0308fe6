// Records filtered in record space (cache/record_filter.h): a constant field stays constant bit
// for bit, a linear field stays exact through the gradients, an edge far beyond the noise is
// kept exactly, independent noise shrinks, the result does not depend on the thread count, and
// the shading pass's lookups read the filtered values while the gathering pass's do not.
#include <gtest/gtest.h>

#include <oneapi/tbb/task_arena.h>

#include <cmath>
#include <random>

#include "bounce/cache/irradiance_cache.h"
#include "bounce/cache/record_filter.h"
#include "bounce/core/parallel.h"

namespace bounce {
namespace {

Bounds box(float s = 10) {
    Bounds b;
    b.extend(Vec3(-s));
    b.extend(Vec3(s));
    return b;
}

CacheSettings filtering(float width) {
    CacheSettings s;
    s.record_filter = width;
    return s;
}

/// 300 records on the plane y = 0 in [-2, 2]^2, each of radius 0.6 (about 25 neighbours), with
/// value field(p) and relative noise `noise`.
template <typename Field>
void fill(IrradianceCache& cache, Field field, float noise, uint64_t seed = 7) {
    std::mt19937 rng(static_cast<unsigned>(seed));
    std::uniform_real_distribution<float> u(-2, 2);
    for (int i = 0; i < 300; ++i) {
        Record r;
        r.p = {u(rng), 0, u(rng)};
        r.n = {0, 1, 0};
        r.E = field(r.p);
        r.ao = 0.5f;
        r.noise = noise;
        r.radius = r.raw_radius = 0.6f;
        r.footprint = 0.6f / 8;
        cache.insert_loaded(r);
    }
}

TEST(RecordFilter, AConstantFieldStaysConstantBitForBit) {
    IrradianceCache cache(box(), filtering(2), false);
    const Color E(0.25f, 0.5f, 1.0f);
    fill(
        cache, [&](const Vec3&) { return E; }, 0.1f);
    auto f = cache.filtered_values();
    ASSERT_EQ(f.size(), cache.size());
    for (const FilteredValue& v : f) {
        EXPECT_EQ(v.E, E);
        EXPECT_EQ(v.ao, 0.5f);
    }
}

TEST(RecordFilter, ALinearFieldStaysExactThroughTheGradients) {
    // Each neighbour is extrapolated to the record with its gradient before it is averaged, so
    // a field the gradients describe is not flattened.
    const Vec3 g{0.3f, 0, -0.2f};
    IrradianceCache cache(box(), filtering(3), false);
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(-2, 2);
    for (int i = 0; i < 300; ++i) {
        Record r;
        r.p = {u(rng), 0, u(rng)};
        r.n = {0, 1, 0};
        r.E = Color(2.0f + dot(g, r.p));
        r.grad_t = {g, g, g};
        r.noise = 0.05f;
        r.radius = r.raw_radius = 0.6f;
        r.footprint = 0.6f / 8;
        cache.insert_loaded(r);
    }
    auto f = cache.filtered_values();
    for (size_t i = 0; i < cache.size(); ++i) EXPECT_NEAR(f[i].E.x, cache.record(i).E.x, 2e-6f);
}

TEST(RecordFilter, AnEdgeFarBeyondTheNoiseIsKeptExactly) {
    // 1 on one side of x = 0, 4 on the other, 2 % noise: the range kernel gives every record
    // across the edge a weight that underflows to 0, and records on its own side agree exactly.
    IrradianceCache cache(box(), filtering(3), false);
    fill(
        cache, [](const Vec3& p) { return Color(p.x < 0 ? 1.0f : 4.0f); }, 0.02f);
    auto f = cache.filtered_values();
    for (size_t i = 0; i < cache.size(); ++i) EXPECT_EQ(f[i].E, cache.record(i).E) << i;
}

TEST(RecordFilter, IndependentNoiseShrinks) {
    // Each record's value is 1 times (1 + 10 % Gaussian noise), its noise estimate 10 %: the
    // filtered values' error falls by about the square root of the neighbours averaged (~25
    // records reach each one, the weights are unequal and the range kernel drops outliers).
    std::mt19937 rng(11);
    std::normal_distribution<float> noise(0, 0.1f);
    IrradianceCache cache(box(), filtering(2), false);
    fill(
        cache, [&](const Vec3&) { return Color(1 + noise(rng)); }, 0.1f);
    auto f = cache.filtered_values();
    double before = 0, after = 0;
    for (size_t i = 0; i < cache.size(); ++i) {
        before += std::pow(cache.record(i).E.x - 1.0, 2);
        after += std::pow(f[i].E.x - 1.0, 2);
    }
    const double gain = std::sqrt(before / after);
    EXPECT_GT(gain, 2.0);
    EXPECT_LT(gain, 6.0);  // no more than the records there are
}

TEST(RecordFilter, DoesNotDependOnTheThreadCount) {
    std::mt19937 rng(13);
    std::normal_distribution<float> noise(0, 0.1f);
    IrradianceCache cache(box(), filtering(2), false);
    fill(
        cache, [&](const Vec3&) { return Color(1 + noise(rng), 0.5f, 0.25f + noise(rng)); }, 0.1f);
    std::vector<FilteredValue> one, many = filter_record_values(cache, 2);
    tbb::task_arena(1).execute([&] { one = filter_record_values(cache, 2); });
    ASSERT_EQ(one.size(), many.size());
    for (size_t i = 0; i < one.size(); ++i) EXPECT_EQ(one[i].E, many[i].E);
}

TEST(RecordFilter, OnlyTheShadingPassReadsFilteredValuesAndOffChangesNothing) {
    std::mt19937 rng(17);
    std::normal_distribution<float> noise(0, 0.1f);
    auto field = [&](const Vec3&) { return Color(1 + noise(rng)); };
    IrradianceCache on(box(), filtering(2), false), off(box(), filtering(0), false);
    fill(on, field, 0.1f, 5);
    rng.seed(17);
    fill(off, field, 0.1f, 5);
    EXPECT_TRUE(off.filtered_values().empty());
    const auto span = on.filtered_values();
    const std::vector<FilteredValue> f(span.begin(), span.end());  // the span ends at the next change
    const Vec3 n{0, 1, 0};
    int moved = 0;
    for (size_t i = 0; i < on.size(); ++i) {
        const Vec3 p = on.record(i).p;
        EXPECT_EQ(on.lookup(p, n, false).E, off.lookup(p, n, false).E);  // gathering: raw values
        Interpolated shaded = on.lookup(p, n, true);
        moved += shaded.E != off.lookup(p, n, true).E;
        // At a record's own point its weight dominates the shading pass's interpolation.
        EXPECT_NEAR(shaded.E.x, f[i].E.x, 0.5f * std::abs(f[i].E.x - on.record(i).E.x) + 0.05f);
    }
    EXPECT_GT(moved, 290);
    // A changed cache is filtered again: a new record far away leaves the old ones' values.
    Record far = on.record(0);
    far.p = {8, 0, 8};
    on.insert_loaded(far);
    auto g = on.filtered_values();
    ASSERT_EQ(g.size(), on.size());
    for (size_t i = 0; i + 1 < g.size(); ++i) EXPECT_EQ(g[i].E, f[i].E);
    EXPECT_EQ(g.back().E, far.E);
}

TEST(RecordFilter, LookupsFromManyThreadsFilterOnceAndAgree) {
    // The first shading lookups of a parallel loop race to filter: one filters (the others
    // wait), and every lookup reads the same values as one thread's.
    std::mt19937 rng(19);
    std::normal_distribution<float> noise(0, 0.1f);
    IrradianceCache cache(box(), filtering(2), false), serial(box(), filtering(2), false);
    fill(
        cache, [&](const Vec3&) { return Color(1 + noise(rng)); }, 0.1f, 9);
    rng.seed(19);
    fill(
        serial, [&](const Vec3&) { return Color(1 + noise(rng)); }, 0.1f, 9);
    std::vector<Color> got(cache.size());
    parallel_for_each_index(size_t(0), got.size(), [&](size_t i) { got[i] = cache.lookup(cache.record(i).p, {0, 1, 0}, true).E; });
    for (size_t i = 0; i < got.size(); ++i) EXPECT_EQ(got[i], serial.lookup(serial.record(i).p, {0, 1, 0}, true).E);
}

}  // namespace
}  // namespace bounce
