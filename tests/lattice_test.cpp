// Sparse radiosity values (radiosity/lattice.h): pages are allocated only where a bake writes,
// zero elsewhere, safe to allocate from many threads, copied and compared whole.
#include <gtest/gtest.h>
#include <tbb/parallel_for.h>

#include "bounce/radiosity/lattice.h"

namespace bounce {
namespace {

/// 1000 triangles of 3 points each (level 1).
std::vector<uint32_t> offsets(uint32_t triangles) {
    std::vector<uint32_t> o;
    for (uint32_t t = 0; t < triangles; ++t) o.push_back(3 * t);
    return o;
}

TEST(LatticeSide, AllocatesOnlyThePagesWrittenAndReadsZeroElsewhere) {
    LatticeSide side;
    const auto o = offsets(1000);
    side.lay_out(o, 3000, 1);
    EXPECT_EQ(side.points(), 3000u);
    EXPECT_EQ(side.allocated_bytes(), 0u);
    EXPECT_EQ(side.run(5, o[5]), nullptr);
    Color* run = side.writable_run(5, o[5]);
    run[2] = Color(7);
    // One page of 64 triangles, 3 points each.
    EXPECT_EQ(side.allocated_bytes(), 64u * 3 * sizeof(Color));
    EXPECT_EQ(side.run(5, o[5]), run);
    EXPECT_EQ(side.value(17), Color(7));
    EXPECT_EQ(side.value(16), Color(0));
    EXPECT_EQ(side.value(2999), Color(0));
    EXPECT_EQ(side.run(64, o[64]), nullptr);  // the next page
    // The last page is partial: 1000 = 15 x 64 + 40 triangles.
    side.writable_run(999, o[999])[0] = Color(1);
    EXPECT_EQ(side.allocated_bytes(), (64u + 40u) * 3 * sizeof(Color));
    EXPECT_EQ(side.value(2997), Color(1));
}

TEST(LatticeSide, ManyThreadsWritingOnePageShareIt) {
    LatticeSide side;
    const auto o = offsets(1000);
    side.lay_out(o, 3000, 2);  // two colours per point (light parts)
    tbb::parallel_for(uint32_t{0}, uint32_t{1000}, [&](uint32_t t) {
        Color* run = side.writable_run(t, o[t]);
        for (uint32_t k = 0; k < 6; ++k) run[k] = Color(static_cast<float>(t));
    });
    EXPECT_EQ(side.allocated_bytes(), 3000u * 2 * sizeof(Color));
    for (uint32_t t = 0; t < 1000; ++t) EXPECT_EQ(side.run(t, o[t])[5], Color(static_cast<float>(t))) << t;
    const LatticeSide copy = side;
    EXPECT_TRUE(copy == side);
    LatticeSide other;
    other.lay_out(o, 3000, 2);
    EXPECT_FALSE(other == side);
    other.writable_run(3, o[3]);  // an allocated page of zeros equals an unallocated one
    LatticeSide empty;
    empty.lay_out(o, 3000, 2);
    EXPECT_TRUE(other == empty);
}

}  // namespace
}  // namespace bounce
