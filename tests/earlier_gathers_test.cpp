// Refinement's earlier gathers in frames of a shot (temporal.h, EarlierGathers): which gathers
// a fragment may blend, the blend's exact value, and how long a gather serves.
#include <gtest/gtest.h>

#include "bounce/cache/temporal.h"

using namespace bounce;

namespace {

/// A refinement gather at (x, 0, z) on the floor (normal +y), a pixel footprint of 0.1.
Record gather_at(float x, float z, Color E, int frame = 1, uint64_t key = 0) {
    Record r;
    r.p = r.origin = Vec3(x, 0, z), r.n = Vec3(0, 1, 0);
    r.E = E, r.ao = 0.5f, r.bent = Vec3(0, 1, 0);
    r.footprint = r.radius = r.raw_radius = 0.1f;
    r.rays = 64, r.key = key, r.frame = r.gathered = frame;
    return r;
}

Bounds box() {
    Bounds b;
    b.extend(Vec3(-2, -2, -2));
    b.extend(Vec3(2, 2, 2));
    return b;
}

}  // namespace

TEST(EarlierGathers, BlendsAgreeingGathersWithATentFilter) {
    // Reach 1 pixel (0.1): gathers 0.05, 0.025 and 0.075 away weigh 1/2, 3/4 and 1/4.
    const std::vector<Record> g = {gather_at(0.05f, 0, Color(1.0f)), gather_at(0, 0.025f, Color(1.04f)),
                                   gather_at(-0.075f, 0, Color(0.96f)), gather_at(0.5f, 0, Color(9.0f))};
    const EarlierGathers earlier(g, box(), 1, 0.1f, 1e-6f);
    const std::optional<Record> b = earlier.blend(Vec3(0), Vec3(0, 1, 0), 0.1f);
    ASSERT_TRUE(b.has_value());
    const float expect = (0.5f * 1.0f + 0.75f * 1.04f + 0.25f * 0.96f) / 1.5f;
    EXPECT_NEAR(b->E[0], expect, 1e-6f);
    EXPECT_NEAR(b->ao, 0.5f, 1e-6f);
    EXPECT_EQ(b->rays, 0u);  // a blend is never itself a gather
}

TEST(EarlierGathers, DisagreeingFewOrOtherSurfacesGatherTheirOwn) {
    const Vec3 up(0, 1, 0);
    // Three around, but across an edge of the light (luminance spread far above 0.1).
    const std::vector<Record> edge = {gather_at(0.05f, 0, Color(1)), gather_at(-0.05f, 0, Color(1)), gather_at(0, 0.05f, Color(3))};
    EXPECT_FALSE(EarlierGathers(edge, box(), 1, 0.1f, 1e-6f).blend(Vec3(0), up, 0.1f).has_value());
    // Two are too few.
    const std::vector<Record> two = {gather_at(0.05f, 0, Color(1)), gather_at(-0.05f, 0, Color(1))};
    EXPECT_FALSE(EarlierGathers(two, box(), 1, 0.1f, 1e-6f).blend(Vec3(0), up, 0.1f).has_value());
    // A step (off the fragment's plane) and another facing do not count.
    std::vector<Record> other = two;
    other.push_back(gather_at(0, 0.05f, Color(1)));
    other.back().origin.y = 0.05f;
    other.push_back(gather_at(0, -0.05f, Color(1)));
    other.back().n = normalize(Vec3(0, 1, 1));
    EXPECT_FALSE(EarlierGathers(other, box(), 1, 0.1f, 1e-6f).blend(Vec3(0), up, 0.1f).has_value());
    // Beyond the reach.
    const std::vector<Record> far = {gather_at(0.11f, 0, Color(1)), gather_at(-0.11f, 0, Color(1)), gather_at(0, 0.11f, Color(1))};
    EXPECT_FALSE(EarlierGathers(far, box(), 1, 0.1f, 1e-6f).blend(Vec3(0), up, 0.1f).has_value());
    EXPECT_TRUE(EarlierGathers(far, box(), 1.2f, 0.1f, 1e-6f).blend(Vec3(0), up, 0.1f).has_value());
}

TEST(EarlierGathers, AGatherServesItsLifespanOfFrames) {
    const std::vector<Record> g = {gather_at(0, 0, Color(1), 1, 7), gather_at(0, 0, Color(1), 5, 3)};
    const EarlierGathers earlier(g, box(), 1, 0.1f, 1e-6f);
    EXPECT_EQ(earlier.lasting(EarlierGathers::kLifespan).size(), 2u);
    const std::vector<Record> later = earlier.lasting(EarlierGathers::kLifespan + 1);
    ASSERT_EQ(later.size(), 1u);
    EXPECT_EQ(later[0].key, 3u);
}
