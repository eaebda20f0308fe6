// core/tiles.h: tiles cover a window's pixels exactly once whatever its size against the tile
// size; a tile's index is its row-major place (tile_index_of agrees at every pixel); the spiral
// order lists the same tiles, the centre's first; for_each_tile runs each tile once.
#include <gtest/gtest.h>

#include <tbb/task_arena.h>

#include <atomic>
#include <vector>

#include "bounce/core/tiles.h"

namespace bounce {
namespace {

TEST(Tiles, CoverEveryPixelOnceInRowMajorIndexAndSpiralFromTheCentre) {
    for (const auto& [w, h, size] : {std::tuple{64, 48, 16}, std::tuple{67, 45, 16}, std::tuple{5, 3, 32}, std::tuple{100, 1, 7}}) {
        const std::vector<Tile> rows = make_tiles(w, h, size);
        std::vector<int> owner(static_cast<size_t>(w * h), -1);
        for (size_t i = 0; i < rows.size(); ++i) {
            const Tile& t = rows[i];
            EXPECT_EQ(t.index, static_cast<int>(i));
            for (int y = t.y0; y < t.y1; ++y)
                for (int x = t.x0; x < t.x1; ++x) {
                    int& o = owner[static_cast<size_t>(y * w + x)];
                    EXPECT_EQ(o, -1) << "pixel in two tiles";
                    o = t.index;
                    EXPECT_EQ(tile_index_of(x, y, w, size), t.index);
                }
        }
        for (int o : owner) EXPECT_GE(o, 0) << "pixel in no tile";
        std::vector<Tile> spiral = make_tiles(w, h, size, TileOrder::Spiral);
        ASSERT_EQ(spiral.size(), rows.size());
        const Tile& first = spiral.front();  // holds the window's centre, or touches it
        EXPECT_LE(first.x0, w / 2 + size);
        EXPECT_GE(first.x1, w / 2 - size);
        std::vector<int> seen(rows.size(), 0);
        for (const Tile& t : spiral) ++seen[static_cast<size_t>(t.index)];
        for (int s : seen) EXPECT_EQ(s, 1);
    }
}

TEST(Tiles, EachTileRunsOnceWhateverTheThreads) {
    const std::vector<Tile> tiles = make_tiles(200, 120, 16, TileOrder::Spiral);
    for (int threads : {1, 2}) {
        std::vector<std::atomic<int>> runs(tiles.size());
        tbb::task_arena(threads).execute([&] { for_each_tile(tiles, [&](const Tile& t) { ++runs[static_cast<size_t>(t.index)]; }); });
        for (const auto& r : runs) EXPECT_EQ(r.load(), 1) << threads;
    }
}

}  // namespace
}  // namespace bounce
