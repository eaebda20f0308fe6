// Refinement's earlier gathers in frames of a shot (temporal.h, EarlierGathers): which gather
// a fragment reuses the rays of, and how long a gather serves.
#include <gtest/gtest.h>

#include "bounce/cache/temporal.h"

using namespace bounce;

namespace {

/// A refinement gather at (x, 0, z) on the floor (normal +y), a pixel footprint of 0.1, with hits.
Record gather_at(float x, float z, int frame = 1, uint64_t key = 0) {
    Record r;
    r.p = r.origin = Vec3(x, 0, z), r.n = Vec3(0, 1, 0);
    r.footprint = r.radius = r.raw_radius = 0.1f;
    r.rays = 64, r.key = key, r.frame = r.gathered = frame;
    r.hits = std::make_shared<GatherHits>();
    return r;
}

Bounds box() {
    Bounds b;
    b.extend(Vec3(-2, -2, -2));
    b.extend(Vec3(2, 2, 2));
    return b;
}

}  // namespace

TEST(EarlierGathers, AFragmentReusesTheNearestGatherOnItsSurface) {
    const Vec3 up(0, 1, 0);
    std::vector<Record> g = {gather_at(0.05f, 0, 1, 1), gather_at(0, 0.03f, 1, 2), gather_at(-0.09f, 0, 1, 3)};
    // Nearer, but a step (off the fragment's plane), another facing, or without hits: not these.
    g.push_back(gather_at(0.01f, 0, 1, 4));
    g.back().origin.y = 0.05f;
    g.push_back(gather_at(0, 0.01f, 1, 5));
    g.back().n = normalize(Vec3(0, 1, 1));
    g.push_back(gather_at(-0.01f, 0, 1, 6));
    g.back().hits.reset();
    const EarlierGathers earlier(g, box(), 1);
    const Record* r = earlier.nearest(Vec3(0), up, 0.1f);
    ASSERT_NE(r, nullptr);
    EXPECT_EQ(r->key, 2u);
    // Beyond the reach (1 footprint): none; a reach of 1.2 footprints takes the one at 0.11.
    const std::vector<Record> far = {gather_at(0.11f, 0, 1, 7)};
    EXPECT_EQ(EarlierGathers(far, box(), 1).nearest(Vec3(0), up, 0.1f), nullptr);
    ASSERT_NE(EarlierGathers(far, box(), 1.2f).nearest(Vec3(0), up, 0.1f), nullptr);
    // Two at the same distance: the first in order (independent of the index's visiting order).
    const std::vector<Record> tie = {gather_at(0.05f, 0, 1, 8), gather_at(-0.05f, 0, 1, 9)};
    EXPECT_EQ(EarlierGathers(tie, box(), 1).nearest(Vec3(0), up, 0.1f)->key, 8u);
}

TEST(EarlierGathers, AGatherServesItsLifespanOfFrames) {
    const std::vector<Record> g = {gather_at(0, 0, 1, 7), gather_at(0, 0, 5, 3)};
    const EarlierGathers earlier(g, box(), 1);
    EXPECT_EQ(earlier.lasting(EarlierGathers::kLifespan).size(), 2u);
    const std::vector<Record> later = earlier.lasting(EarlierGathers::kLifespan + 1);
    ASSERT_EQ(later.size(), 1u);
    EXPECT_EQ(later[0].key, 3u);
}
