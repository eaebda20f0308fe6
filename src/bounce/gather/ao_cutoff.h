// Internal to gather/: the translational gradient of ambient occlusion that a distance cutoff
// (ao_distance) adds. Ward and Heckbert's boundary sums treat every boundary between an
// occluded and an unoccluded cell as an occluding edge, moving as seen from the gather point at
// its distance. Where the cutoff sphere cuts a continuous surface (a wall 0.6 away with
// ao_distance 1), the boundary is instead the line on that surface at distance ao_distance,
// and it moves with the surface's distance: moving the point parallel to a plane moves nothing,
// towards it the boundary sweeps by the change of distance over its rate across the cells. The
// edge form got 65 % of the finite-difference gradient there and nothing where the wall sits at
// the cutoff itself (docs/gather.md, "AO with a cutoff"), which left bands of interpolation
// error along every corner of the Cornell box.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "bounce/core/math.h"
#include "bounce/gather/gather.h"

namespace bounce::detail {

/// One gather's cells as the cutoff term reads them (row-major, cell j * n + k): directions
/// `D`, distances `R` (INFINITY: escaped), unoccluded fractions `U` and the geometric normals
/// of the hits `NH` (0: escaped or a strand of fur, never a continuous surface).
struct CutoffCells {
    std::span<const Vec3> D;
    std::span<const float> R, U;
    std::span<const Vec3> NH;
};

/// Which neighbouring cells of a gather hit one continuous surface: each hit lies near the
/// other's tangent plane. Such a pair's difference in occlusion comes from distance alone (the
/// cutoff or the falloff), not from an edge. Each pair is judged at most once per gather, when
/// one of the two sums first asks.
class SurfacePairs {
  public:
    SurfacePairs(const GatherGrid& grid, const CutoffCells& cells);
    /// Whether neighbouring cells a and b (either order) are such a pair.
    bool operator()(size_t a, size_t b) const;
    /// The gradient of AO (a mean over the cells) from every such pair:
    /// (U_b - U_a) g / ((t_b - t_a) S), g = dt/dx, each family of pairs (azimuthal, radial)
    /// weighed by its share of the distance's rate across the cells, so that a boundary
    /// crossing both families is counted once.
    Vec3 gradient() const;

  private:
    GatherGrid grid_;
    const CutoffCells& cells_;
    /// Cell c with its azimuthal (k + 1) and radial (j + 1) neighbour: 1 one surface, 0 not,
    /// -1 not asked yet (most pairs never are: both sums read only pairs near a boundary).
    mutable std::vector<int8_t> next_k_, next_j_;
    size_t cell(int j, int k) const { return static_cast<size_t>(j * grid_.n + ((k + grid_.n) % grid_.n)); }
    bool next(size_t c, bool radial) const;
    /// t_b - t_a between neighbours on one surface, else 0.
    float step(int j, int k, bool radial) const;
};

}  // namespace bounce::detail
