// Sparse radiosity values (radiosity/lattice.h): pages are allocated only where a bake writes,
// zero elsewhere, safe to allocate from many threads, copied and compared whole.
#include <gtest/gtest.h>

#include "bounce/core/parallel.h"
#include "bounce/radiosity/lattice.h"

namespace bounce {
namespace {

/// Triangles of 3 points each (level 1).
std::shared_ptr<const std::vector<uint32_t>> offsets(uint32_t triangles) {
    auto o = std::make_shared<std::vector<uint32_t>>();
    for (uint32_t t = 0; t < triangles; ++t) o->push_back(3 * t);
    return o;
}

TEST(LatticeSide, AllocatesOnlyThePagesWrittenAndReadsZeroElsewhere) {
    LatticeSide side;
    const auto shared = offsets(1000);
    const std::vector<uint32_t>& o = *shared;
    side.lay_out(shared, 3000, 1);
    EXPECT_EQ(side.points(), 3000u);
    EXPECT_EQ(side.allocated_bytes(), 0u);
    EXPECT_EQ(side.run(5, o[5]), nullptr);
    Color* run = side.writable_run(5, o[5]);
    run[2] = Color(7);
    // One page of 32 triangles, 3 points each.
    EXPECT_EQ(side.allocated_bytes(), 32u * 3 * sizeof(Color));
    EXPECT_EQ(side.run(5, o[5]), run);
    EXPECT_EQ(side.value(17), Color(7));
    EXPECT_EQ(side.value(16), Color(0));
    EXPECT_EQ(side.value(2999), Color(0));
    EXPECT_EQ(side.run(32, o[32]), nullptr);  // the next page
    // The last page is partial: 1000 = 31 x 32 + 8 triangles.
    side.writable_run(999, o[999])[0] = Color(1);
    EXPECT_EQ(side.allocated_bytes(), (32u + 8u) * 3 * sizeof(Color));
    EXPECT_EQ(side.value(2997), Color(1));
}

TEST(LatticeSide, ManyThreadsWritingOnePageShareIt) {
    LatticeSide side;
    const auto shared = offsets(1000);
    const std::vector<uint32_t>& o = *shared;
    side.lay_out(shared, 3000, 2);                                          // two colours per point (light parts)
    parallel_for_each_index(uint32_t{0}, uint32_t{1000}, [&](uint32_t t) {  // (TBB's own loops are not instrumented under TSan)
        Color* run = side.writable_run(t, o[t]);
        for (uint32_t k = 0; k < 6; ++k) run[k] = Color(static_cast<float>(t));
    });
    EXPECT_EQ(side.allocated_bytes(), 3000u * 2 * sizeof(Color));
    for (uint32_t t = 0; t < 1000; ++t) EXPECT_EQ(side.run(t, o[t])[5], Color(static_cast<float>(t))) << t;
    const LatticeSide copy = side;
    EXPECT_TRUE(copy == side);
    LatticeSide other;
    other.lay_out(shared, 3000, 2);
    EXPECT_FALSE(other == side);
    other.writable_run(3, o[3]);  // an allocated page of zeros equals an unallocated one
    LatticeSide empty;
    empty.lay_out(shared, 3000, 2);
    EXPECT_TRUE(other == empty);
}

TEST(SideStates, AreZeroUntilASideLeavesZeroAndThenPagedByThreads) {
    SideStates states(2000);
    EXPECT_EQ(states.size(), 2000u);
    EXPECT_EQ(states.load(1999, std::memory_order_relaxed), 0);
    states.store(5, 0, std::memory_order_relaxed);  // allocates nothing, reads 0
    EXPECT_EQ(states.load(5, std::memory_order_relaxed), 0);
    parallel_for_each_index(size_t{0}, size_t{2000}, [&](size_t i) {
        uint8_t expected = 0;
        if (i % 3 == 0) states.at(i).compare_exchange_strong(expected, 2);
    });
    for (size_t i = 0; i < 2000; ++i) EXPECT_EQ(states.load(i, std::memory_order_relaxed), i % 3 == 0 ? 2 : 0) << i;
    SideStates moved = std::move(states);
    EXPECT_EQ(moved.load(1998, std::memory_order_relaxed), 2);
}

}  // namespace
}  // namespace bounce
