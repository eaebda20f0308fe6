// The gather's grid of cells (gather.h): how many strata, the direction each cell's ray takes
// with a random stream, which cell or view-summary bin a direction falls in, the order packets
// trace them in, and which cells a moving object's bounds may cross.
#include <algorithm>
#include <cmath>
#include <vector>

#include "bounce/gather/gather.h"

namespace bounce {

GatherGrid gather_grid(int rays) {
    GatherGrid g;
    g.m = std::max(1, static_cast<int>(std::lround(std::sqrt(static_cast<double>(rays) / kPi))));
    g.n = std::max(1, static_cast<int>(std::lround(static_cast<double>(rays) / g.m)));
    return g;
}

int grid_cell(const GatherGrid& grid, const Vec3& local) {
    const float sin2 = std::clamp(1 - local.z * local.z, 0.0f, 1.0f);
    float phi = std::atan2(local.y, local.x);
    if (phi < 0) phi += 2 * kPi;
    const int j = std::min(grid.m - 1, static_cast<int>(sin2 * static_cast<float>(grid.m)));
    const int k = std::min(grid.n - 1, static_cast<int>(phi * (static_cast<float>(grid.n) / (2 * kPi))));
    return j * grid.n + k;
}

int direction_bin(const Vec3& local) { return grid_cell(GatherGrid{kReachBands, kReachSectors}, local); }

Vec3 gather_cell_direction(const GatherGrid& grid, int j, int k, float u, float v) {
    float sin2 = (static_cast<float>(j) + u) / static_cast<float>(grid.m);
    float phi = 2 * kPi * (static_cast<float>(k) + v) / static_cast<float>(grid.n);
    float sin_t = std::sqrt(sin2), cos_t = std::sqrt(std::max(0.0f, 1 - sin2));
    return {sin_t * std::cos(phi), sin_t * std::sin(phi), cos_t};
}

Vec3 gather_cell_direction(const GatherGrid& grid, int j, int k, const RandomStream& rng) {
    const auto c = static_cast<uint64_t>(j * grid.n + k);
    return gather_cell_direction(grid, j, k, rng.get(c, kDimGather), rng.get(c, kDimGather + 1));
}

void gather_local_directions(const GatherGrid& grid, const RandomStream& rng, std::vector<Vec3>& out) {
    out.resize(static_cast<size_t>(grid.rays()));
    for (int j = 0; j < grid.m; ++j)
        for (int k = 0; k < grid.n; ++k) out[static_cast<size_t>(j * grid.n + k)] = gather_cell_direction(grid, j, k, rng);
}

std::vector<uint32_t> gather_packet_order(const GatherGrid& grid) {
    // Packets of 16 rays are traversed together; 4x4 blocks of neighbouring (elevation,
    // azimuth) cells point in nearby directions, a row segment of 16 azimuths does not.
    std::vector<uint32_t> order;
    order.reserve(static_cast<size_t>(grid.rays()));
    for (int j0 = 0; j0 < grid.m; j0 += 4)
        for (int k0 = 0; k0 < grid.n; k0 += 4)
            for (int j = j0; j < std::min(j0 + 4, grid.m); ++j)
                for (int k = k0; k < std::min(k0 + 4, grid.n); ++k) order.push_back(static_cast<uint32_t>(j * grid.n + k));
    return order;
}

void cells_through(const GatherGrid& grid, const Vec3& p, const Vec3& n, const RandomStream& rng, const GatherHits& hits,
                   std::span<const Bounds> boxes, std::vector<uint32_t>& out) {
    const Frame frame(n);
    for (int j = 0; j < grid.m; ++j)
        for (int k = 0; k < grid.n; ++k) {
            const auto c = static_cast<size_t>(j * grid.n + k);
            const Vec3 d = frame.to_world(gather_cell_direction(grid, j, k, rng));
            const float end = hits.t[c];
            for (const Bounds& b : boxes) {
                // Slab test of the segment [0, end] from p along d against the box.
                float t0 = 0, t1 = end;
                for (int a = 0; a < 3 && t0 <= t1; ++a) {
                    const float inv = 1 / d[a];
                    float lo = (b.lo[a] - p[a]) * inv, hi = (b.hi[a] - p[a]) * inv;
                    if (lo > hi) std::swap(lo, hi);
                    if (std::isnan(lo) || std::isnan(hi)) {  // parallel to the slab: inside it or not
                        if (p[a] < b.lo[a] || p[a] > b.hi[a]) t0 = INFINITY;
                        continue;
                    }
                    t0 = std::max(t0, lo), t1 = std::min(t1, hi);
                }
                if (t0 <= t1) {
                    out.push_back(static_cast<uint32_t>(c));
                    break;
                }
            }
        }
}

}  // namespace bounce
