// gather/grid.h exactly: a grid of about `rays` strata; each cell's direction lies in its own
// stratum (grid_cell inverts gather_cell_direction) on the unit upper hemisphere; the strata hold
// equal cosine-weighted measure (so the mean of cos over uniform jitter is 2/3, the cosine
// distribution's); the packet order visits every cell once; direction bins hold 1/32 each.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "bounce/gather/grid.h"

namespace bounce {
namespace {

TEST(GatherGrid, EveryCellsDirectionLiesInItsOwnStratumAndTheOrderVisitsEachOnce) {
    for (int rays : {16, 64, 256, 1024}) {
        const GatherGrid g = gather_grid(rays);
        EXPECT_NEAR(g.rays(), rays, 0.15 * rays) << rays;
        for (int j = 0; j < g.m; ++j)
            for (int k = 0; k < g.n; ++k)
                for (const auto& [u, v] : {std::pair{0.01f, 0.01f}, std::pair{0.5f, 0.5f}, std::pair{0.99f, 0.2f}}) {
                    const Vec3 d = gather_cell_direction(g, j, k, u, v);
                    EXPECT_NEAR(length(d), 1, 1e-5f);
                    EXPECT_GT(d.z, 0);
                    EXPECT_EQ(grid_cell(g, d), j * g.n + k) << rays << " " << j << " " << k;
                }
        std::vector<uint32_t> order = gather_packet_order(g);
        ASSERT_EQ(order.size(), static_cast<size_t>(g.rays()));
        std::sort(order.begin(), order.end());
        for (size_t i = 0; i < order.size(); ++i) EXPECT_EQ(order[i], i);
    }
}

TEST(GatherGrid, StrataHoldEqualCosineWeightedMeasure) {
    // With jitter at the centre of a fine sub-grid, the mean of cos(theta) over all cells is the
    // cosine distribution's 2/3, and every direction bin gets 1/32 of the samples.
    const GatherGrid g = gather_grid(1024);
    double cos_sum = 0;
    std::vector<int> bins(kReachBins, 0);
    int count = 0;
    for (int j = 0; j < g.m; ++j)
        for (int k = 0; k < g.n; ++k)
            for (int a = 0; a < 8; ++a)
                for (int b = 0; b < 8; ++b) {
                    const Vec3 d = gather_cell_direction(g, j, k, (static_cast<float>(a) + 0.5f) / 8, (static_cast<float>(b) + 0.5f) / 8);
                    cos_sum += d.z;
                    ++bins[static_cast<size_t>(direction_bin(d))];
                    ++count;
                }
    EXPECT_NEAR(cos_sum / count, 2.0 / 3.0, 2e-4);
    for (int n : bins) EXPECT_NEAR(static_cast<double>(n) / count, 1.0 / kReachBins, 0.004);
}

}  // namespace
}  // namespace bounce
