// scene/texel_lookup.h against hand-computed values on a 4x2 image whose texel (x, y) holds
// 10 y + x: texel centres read exactly, midway between two centres reads their mean, the image
// wraps around at every edge (u + 1 reads as u; a negative u too), row 0 is the top (v = 1), and
// a uv that is not finite reads texel (0, 0).
#include <gtest/gtest.h>

#include <cmath>

#include "bounce/core/math.h"
#include "bounce/scene/texel_lookup.h"

namespace bounce {
namespace {

float look(float u, float v) {
    return periodic_bilinear(4, 2, {u, v}, [](size_t x, size_t y) { return static_cast<float>(10 * y + x); });
}

TEST(TexelLookup, CentresMidpointsWrapAndNonFiniteUvs) {
    // Texel (x, y)'s centre: u = (x + 0.5) / 4, v = 1 - (y + 0.5) / 2.
    EXPECT_FLOAT_EQ(look(0.125f, 0.75f), 0);    // (0, 0), top row
    EXPECT_FLOAT_EQ(look(0.625f, 0.75f), 2);    // (2, 0)
    EXPECT_FLOAT_EQ(look(0.375f, 0.25f), 11);   // (1, 1), bottom row
    EXPECT_FLOAT_EQ(look(0.25f, 0.75f), 0.5f);  // between (0, 0) and (1, 0)
    EXPECT_FLOAT_EQ(look(0.375f, 0.5f), 6);     // between (1, 0) and (1, 1)
    // Past the right edge: between (3, 0) and (0, 0) wrapped.
    EXPECT_FLOAT_EQ(look(1.0f, 0.75f), 1.5f);
    EXPECT_FLOAT_EQ(look(1.125f, 0.75f), look(0.125f, 0.75f));
    EXPECT_FLOAT_EQ(look(-0.875f, 0.25f), look(0.125f, 0.25f));
    EXPECT_FLOAT_EQ(look(0.125f, 1.75f), look(0.125f, 0.75f));
    EXPECT_FLOAT_EQ(look(NAN, 0.3f), 0);
    EXPECT_FLOAT_EQ(look(0.5f, INFINITY), 0);
    // A Color texel interpolates each channel alike.
    const Color c = periodic_bilinear(2, 1, {0.5f, 0.5f}, [](size_t x, size_t) { return x == 0 ? Color(1, 0, 0) : Color(0, 0, 1); });
    EXPECT_FLOAT_EQ(c.x, 0.5f);
    EXPECT_FLOAT_EQ(c.z, 0.5f);
}

}  // namespace
}  // namespace bounce
