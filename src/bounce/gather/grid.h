// The gather's grid of cells: how many strata, the direction each cell's ray takes with a random
// stream, which cell or view-summary bin a direction falls in, the order packets trace them in,
// what each ray hit, and which cells a moving object's bounds may cross.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "bounce/core/math.h"
#include "bounce/core/random.h"

namespace bounce {

/// The stratification used for `rays`.
struct GatherGrid {
    int m = 1, n = 1;  ///< elevation and azimuth strata
    int rays() const { return m * n; }
};
GatherGrid gather_grid(int rays);
/// The direction, in the gather point's frame (z = normal), of the ray of cell (j, k) with
/// jitter (u, v) in [0,1)^2: cosine-weighted, sin^2(theta) stratified by j and phi by k.
Vec3 gather_cell_direction(const GatherGrid& grid, int j, int k, float u, float v);
/// The same with the jitter a gather with stream `rng` draws for that cell.
Vec3 gather_cell_direction(const GatherGrid& grid, int j, int k, const RandomStream& rng);
/// Every cell's direction of a gather with `rng` (cell j * n + k), in its frame: the rays
/// Gatherer::gather traces.
void gather_local_directions(const GatherGrid& grid, const RandomStream& rng, std::vector<Vec3>& out);
/// The cell (j * n + k) of `grid` whose stratum holds direction `local` (z > 0).
int grid_cell(const GatherGrid& grid, const Vec3& local);
/// The order in which a gather traces its grid's cells (index j * n + k): 4x4 blocks of
/// neighbouring cells, so each packet of 16 rays points in nearby directions.
std::vector<uint32_t> gather_packet_order(const GatherGrid& grid);

/// Direction bins of a gather's view summary (GatherResult::reach): its elevation strata in
/// kReachBands bands, its azimuth strata in kReachSectors sectors. Frames of a shot test moving
/// geometry and changed light against them (cache/temporal.h).
inline constexpr int kReachBands = 4, kReachSectors = 8, kReachBins = kReachBands * kReachSectors;
/// The bin of a direction `local` in a gather's frame (z = its normal; z > 0): band by sin^2
/// of its elevation in quarters, sector by azimuth in eighths. Every bin holds 1/32 of the
/// cosine-weighted hemisphere (pi/32 of its cosine-weighted measure).
int direction_bin(const Vec3& local);

/// A gather's ray hits, per cell: what a re-shade traces again for free when only the light its
/// rays found has changed (Gatherer::reshade).
struct GatherHits {
    int m = 0, n = 0;                    ///< the gather's grid (GatherGrid)
    std::vector<float> t, u, v;          ///< distance (INFINITY: escaped) and the hit's (u, v)
    std::vector<uint32_t> object, prim;  ///< object (kNoHit: escaped; | kHairBit: a strand) and primitive
    static constexpr uint32_t kHairBit = 0x80000000u;
    size_t bytes() const { return t.size() * (3 * sizeof(float) + 2 * sizeof(uint32_t)); }
};

/// An earlier gather whose rays a nearby one may reuse (Gatherer::reproject): where it was made,
/// about which normal, with which random stream, and what each ray hit.
struct EarlierGather {
    Vec3 p, n;
    RandomStream rng;
    const GatherHits& hits;
};

/// The cells of a gather (at p about n with `rng` and `grid`) whose rays, as `hits` recorded
/// them, pass through any of `boxes` (an escaped ray: anywhere along it): the rays a moving
/// object may now stop or let through. Appended to `out`.
void cells_through(const GatherGrid& grid, const Vec3& p, const Vec3& n, const RandomStream& rng, const GatherHits& hits,
                   std::span<const Bounds> boxes, std::vector<uint32_t>& out);

}  // namespace bounce
