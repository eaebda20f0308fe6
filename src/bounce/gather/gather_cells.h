// Internal to gather/: the per-cell scratch of a thread's current gather (trace, re-shade or
// reproject, then Gatherer::finish), handed explicitly from step to step (Gatherer::scratch).
#pragma once

#include <cmath>
#include <vector>

#include "bounce/accel/accel.h"
#include "bounce/core/math.h"
#include "bounce/core/scratch.h"
#include "bounce/gather/guide.h"

namespace bounce::detail {

struct Cells {
    std::vector<Color> L, P;  ///< radiance per cell; with light parts, per cell and light (cell-major)
    std::vector<float> R, U, cos_theta;
    std::vector<Vec3> D;
    std::vector<Vec3> NH;  ///< hits' geometric normals, set by Gatherer::finish (0: escaped or fur; ao_cutoff.h)
    std::vector<Hit> hits, packet_hits;
    std::vector<Vec3> packet_dirs;
    GuidedRays guided;      ///< a guided gather's rays and their shares (Gatherer::gather_guided)
    ScratchBuffer scratch;  ///< what the gather's steps take for themselves (hessian.h, reprojection), handed down
    void resize(size_t s) {
        L.assign(s, Color(0));
        R.assign(s, INFINITY);
        U.assign(s, 1.0f);
        D.resize(s), NH.resize(s), cos_theta.resize(s), hits.resize(s), packet_dirs.resize(s), packet_hits.resize(s);
    }
};

/// Per cell of `grid`, the cells within `margin` radians of it (any of their directions, from
/// the cells' centres and widths), itself included (reproject.cpp).
std::vector<std::vector<uint32_t>> cell_margins(const GatherGrid& grid, float margin);

}  // namespace bounce::detail
