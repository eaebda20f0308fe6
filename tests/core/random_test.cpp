// core/random.h: a stream is a pure function of (seed, keys, sample, dimension) — the same
// numbers in any order, on any thread — in [0, 1) with the moments of a uniform variable, and
// streams of other keys or dimensions uncorrelated.
#include <gtest/gtest.h>

#include <cmath>

#include "bounce/core/random.h"

namespace bounce {
namespace {

TEST(Random, AStreamIsAFunctionOfItsKeysUniformAndUncorrelated) {
    const RandomStream a(5, 17, 3), same(5, 17, 3), other(5, 18, 3), reseeded(6, 17, 3);
    const int n = 200000;
    double sum = 0, sum2 = 0, cross = 0, cross_dims = 0;
    int equal_other = 0;
    for (int i = n - 1; i >= 0; --i) {  // backwards: order does not matter
        const float x = a.get(i, 0);
        ASSERT_EQ(x, same.get(i, 0));
        ASSERT_GE(x, 0.0f);
        ASSERT_LT(x, 1.0f);
        sum += x, sum2 += double(x) * x;
        cross += (x - 0.5) * (other.get(i, 0) - 0.5);
        cross_dims += (x - 0.5) * (a.get(i, 1) - 0.5);
        equal_other += x == reseeded.get(i, 0);
    }
    EXPECT_NEAR(sum / n, 0.5, 3e-3);
    EXPECT_NEAR(sum2 / n - (sum / n) * (sum / n), 1.0 / 12.0, 2e-3);
    // Covariance of independent uniforms is 0 (its standard error at n samples is 1/12/sqrt(n)).
    EXPECT_NEAR(cross / n, 0.0, 1e-3);
    EXPECT_NEAR(cross_dims / n, 0.0, 1e-3);
    EXPECT_LT(equal_other, 10);
}

}  // namespace
}  // namespace bounce
