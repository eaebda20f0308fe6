// core/sampling.h against integrals it must reproduce: stratified samples put exactly one point
// in each cell of the largest square grid, the cosine-weighted hemisphere has pdf cos/pi (its
// mean cosine is 2/3, its directions unit and above the plane), and the concentric map is onto
// the unit disc and area preserving (a quarter of the square's samples in each quadrant's
// quarter of the disc, the mean squared radius 1/2).
#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "bounce/core/random.h"
#include "bounce/core/sampling.h"

namespace bounce {
namespace {

TEST(Sampling, StratifiedSamplesFillEachCellOfTheGridOnce) {
    const RandomStream rng(7, 1);
    for (int n : {1, 4, 9, 16, 17, 64}) {
        const int nx = static_cast<int>(std::sqrt(static_cast<float>(n)));
        std::set<std::pair<int, int>> cells;
        for (int i = 0; i < nx * nx; ++i) {
            const Vec2 s = stratified_2d(i, n, rng.get(i, 0), rng.get(i, 1));
            ASSERT_GE(s.x, 0.0f);
            ASSERT_LT(s.x, 1.0f);
            cells.insert({static_cast<int>(s.x * static_cast<float>(nx)), static_cast<int>(s.y * static_cast<float>(nx))});
        }
        EXPECT_EQ(cells.size(), static_cast<size_t>(nx * nx)) << n;
        // Beyond the grid a sample is its jitter, unchanged.
        if (n > nx * nx) {
            EXPECT_EQ(stratified_2d(n - 1, n, 0.25f, 0.75f).y, 0.75f);
        }
    }
}

TEST(Sampling, TheCosineHemisphereHasMeanCosineTwoThirds) {
    const RandomStream rng(11, 2);
    const int n = 256 * 256;
    double sum_cos = 0, sum_cos2 = 0;
    for (int i = 0; i < n; ++i) {
        const Vec2 u = stratified_2d(i, n, rng.get(i, 0), rng.get(i, 1));
        const Vec3 w = cosine_hemisphere(u.x, u.y);
        ASSERT_NEAR(length(w), 1.0f, 1e-5f);
        ASSERT_GE(w.z, 0.0f);
        sum_cos += w.z, sum_cos2 += w.z * w.z;
    }
    // E[cos] = int cos (cos / pi) dw = 2/3; E[cos^2] = 1/2.
    EXPECT_NEAR(sum_cos / n, 2.0 / 3.0, 1e-4);
    EXPECT_NEAR(sum_cos2 / n, 0.5, 1e-4);
}

TEST(Sampling, TheConcentricMapIsOntoTheDiscAndPreservesArea) {
    const int n = 200;
    double sum_r2 = 0;
    int quadrant[4] = {0, 0, 0, 0};
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            const float fn = static_cast<float>(n);
            const Vec2 d = concentric_disc((static_cast<float>(i) + 0.5f) / fn, (static_cast<float>(j) + 0.5f) / fn);
            const float r2 = d.x * d.x + d.y * d.y;
            ASSERT_LE(r2, 1.0f + 1e-6f);
            sum_r2 += r2;
            ++quadrant[(d.x < 0 ? 1 : 0) + (d.y < 0 ? 2 : 0)];
        }
    EXPECT_NEAR(sum_r2 / (n * n), 0.5, 1e-3);  // uniform on the disc: E[r^2] = 1/2
    for (int q : quadrant) EXPECT_EQ(q, n * n / 4);
    EXPECT_EQ(concentric_disc(0.5f, 0.5f).x, 0.0f);
    EXPECT_NEAR(concentric_disc(1, 0.5f).x, 1.0f, 1e-6f);  // the square's edge to the circle
}

}  // namespace
}  // namespace bounce
