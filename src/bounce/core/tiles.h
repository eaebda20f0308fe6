// Image tiles (buckets) and the greedy way threads take them: every worker pulls the next tile
// of the list until none is left, so the list's order is the order work starts in.
#pragma once

#include <tbb/task_arena.h>

#include <atomic>
#include <string>
#include <vector>

#include "bounce/core/parallel.h"

namespace bounce {

struct Tile {
    int index = 0;       ///< row-major index: results that depend on tiles use this order
    int x0 = 0, y0 = 0;  ///< first pixel (window coordinates)
    int x1 = 0, y1 = 0;  ///< one past the last
};

/// The order threads take tiles in: row-major, or centre first and outwards (the subject
/// usually shows first). Never changes the image.
enum class TileOrder : uint8_t { Rows, Spiral };

/// Tiles of `size` pixels covering a width x height window, listed in `order`.
std::vector<Tile> make_tiles(int width, int height, int size, TileOrder order = TileOrder::Rows);
/// The row-major index (Tile::index) of the tile that holds pixel (x, y) of a `width`-wide image.
inline int tile_index_of(int x, int y, int width, int size) { return (y / size) * ((width + size - 1) / size) + x / size; }

/// Calls fn(tile) for every tile, in parallel in the current task arena; each worker takes the
/// next tile of the list when it is free (greedy load balancing).
template <typename Fn>
void for_each_tile(const std::vector<Tile>& tiles, Fn&& fn) {
    std::atomic<size_t> next{0};
    const int workers = std::min<int>(tbb::this_task_arena::max_concurrency(), static_cast<int>(tiles.size()));
    parallel_ranges(
        0, workers, 1,
        [&](int, int) {
            for (size_t i = next.fetch_add(1, std::memory_order_relaxed); i < tiles.size();
                 i = next.fetch_add(1, std::memory_order_relaxed))
                fn(tiles[i]);
        },
        true);
}

}  // namespace bounce
