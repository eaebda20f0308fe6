// The per-thread scratch arena (core/scratch.h): what is taken stays put while more is taken,
// nested scopes keep their callers' memory, and a piece of work the size of the last takes no
// new memory once the outermost scope has closed.
#include <gtest/gtest.h>

#include <cstdint>
#include <numeric>

#include "bounce/core/scratch.h"

namespace bounce {
namespace {

TEST(ScratchBuffer, TakenSpansStayPutWhileItGrowsAndAreFilled) {
    ScratchBuffer s;
    const auto scope = s.scope();
    std::span<uint8_t> flags = s.take<uint8_t>(3, 7);
    std::span<double> values = s.take<double>(5, 0.5);  // aligned after 3 bytes
    EXPECT_EQ(reinterpret_cast<uintptr_t>(values.data()) % alignof(double), 0u);
    for (uint8_t f : flags) EXPECT_EQ(f, 7);
    for (double v : values) EXPECT_EQ(v, 0.5);
    std::iota(values.begin(), values.end(), 1.0);
    std::span<double> big = s.take<double>(100000, 2.0);  // a block of its own
    EXPECT_EQ(big.size(), 100000u);
    EXPECT_EQ(big.back(), 2.0);
    EXPECT_EQ(values[0], 1.0);  // the first block was kept, not moved
    EXPECT_EQ(values[4], 5.0);
    EXPECT_EQ(flags[2], 7);
}

TEST(ScratchBuffer, ANestedScopeKeepsItsCallersMemoryAndTheOutermostGivesItBack) {
    ScratchBuffer s;
    {
        const auto outer = s.scope();
        std::span<int> mine = s.take<int>(10, 3);
        {
            const auto inner = s.scope();
            std::span<int> theirs = s.take<int>(10000, 4);
            EXPECT_EQ(theirs[9999], 4);
        }
        EXPECT_EQ(mine[9], 3);  // the inner scope's close gave nothing back
        std::span<int> more = s.take<int>(10, 5);
        EXPECT_NE(more.data(), mine.data());
    }
    // Merged into one block as large as all that was taken: the same piece again allocates nothing.
    const size_t held = s.capacity();
    EXPECT_GE(held, (10 + 10000 + 10) * sizeof(int));
    const void* first = nullptr;
    {
        const auto again = s.scope();
        first = s.take<int>(10, 0).data();
        s.take<int>(10000, 0);
        s.take<int>(10, 0);
        EXPECT_EQ(s.capacity(), held);
    }
    {
        const auto again = s.scope();
        EXPECT_EQ(s.take<int>(10, 0).data(), first);  // reused from the start
    }
}

}  // namespace
}  // namespace bounce
