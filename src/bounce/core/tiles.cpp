#include "bounce/core/tiles.h"

#include <algorithm>
#include <cmath>

namespace bounce {

std::vector<Tile> make_tiles(int width, int height, int size, TileOrder order) {
    size = std::max(size, 1);
    const int tx = (width + size - 1) / size, ty = (height + size - 1) / size;
    std::vector<Tile> tiles;
    tiles.reserve(static_cast<size_t>(std::max(tx * ty, 0)));
    for (int j = 0; j < ty; ++j)
        for (int i = 0; i < tx; ++i)
            tiles.push_back({j * tx + i, i * size, j * size, std::min((i + 1) * size, width), std::min((j + 1) * size, height)});
    if (order == TileOrder::Spiral) {
        // By distance of the tile centre from the image centre, ties in row-major order: a
        // square-ish spiral outwards without walking one.
        const double cx = 0.5 * width, cy = 0.5 * height;
        auto dist = [&](const Tile& t) { return std::max(std::abs(0.5 * (t.x0 + t.x1) - cx), std::abs(0.5 * (t.y0 + t.y1) - cy)); };
        std::stable_sort(tiles.begin(), tiles.end(), [&](const Tile& a, const Tile& b) { return dist(a) < dist(b); });
    }
    return tiles;
}

}  // namespace bounce
