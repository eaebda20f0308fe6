// What a gather's cells give besides their sum (gather.cpp's finish): the gradients' sums over
// the grid (a template over one channel or three), the value's relative standard error, the
// occlusion-aware Hessian, and the view summary's per-bin means.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <span>
#include <vector>

#include "bounce/core/scratch.h"
#include "bounce/gather/gather.h"
#include "bounce/gather/hessian.h"

namespace bounce {

inline float chan(float v, int) { return v; }
inline float chan(const Color& v, int c) { return v[c]; }

/// Rotational gradient (cell-centre angles): sum_k t(phi_k) sum_j tan(theta_j) L_jk, and the
/// translational one, Ward-Heckbert over cell boundaries with min distances (docs/gather.md has
/// the derivation and the sign convention), of the values L[c * stride] (C channels), unscaled.
/// A pair of cells `skip` names moves no boundary (AO's pairs on one surface: ao_cutoff.h).
struct NoSkip {
    bool operator()(size_t, size_t) const { return false; }
};
template <class V, size_t C, class Skip = NoSkip>
void gradient_sums(const GatherGrid& grid, const Frame& frame, float near, const float* R, const V* L, size_t stride,
                   std::array<Vec3, C>& gr, std::array<Vec3, C>& gt, const Skip& skip = {}) {
    const int M = grid.m, N = grid.n;
    const auto fM = static_cast<float>(M);
    const auto at = [&](int j, int k) -> const V& { return L[static_cast<size_t>(j * N + k) * stride]; };
    for (int k = 0; k < N; ++k) {
        float phi_c = 2 * kPi * (static_cast<float>(k) + 0.5f) / static_cast<float>(N);
        float phi_0 = 2 * kPi * static_cast<float>(k) / static_cast<float>(N);
        Vec3 t_c = frame.to_world({-std::sin(phi_c), std::cos(phi_c), 0});
        Vec3 u_c = frame.to_world({std::cos(phi_c), std::sin(phi_c), 0});
        Vec3 t_0 = frame.to_world({-std::sin(phi_0), std::cos(phi_0), 0});
        V rot(0), radial(0), azim(0);
        const int kprev = (k + N - 1) % N;
        for (int j = 0; j < M; ++j) {
            const auto c = static_cast<size_t>(j * N + k);
            float sin_c = std::sqrt((static_cast<float>(j) + 0.5f) / fM);
            float tan_c = sin_c / std::sqrt(std::max(1e-6f, 1 - sin_c * sin_c));
            rot += at(j, k) * tan_c;
            float sin_lo = std::sqrt(static_cast<float>(j) / fM), sin_hi = std::sqrt((static_cast<float>(j) + 1) / fM);
            if (j >= 1) {  // boundary between rows j-1 and j moves radially
                const auto cp = static_cast<size_t>((j - 1) * N + k);
                float rmin = std::max(near, std::min(R[c], R[cp]));
                if (std::isfinite(rmin) && rmin > 0 && !skip(cp, c))  // a hit at 0 (a fold of a displaced surface) moves nothing
                    radial += (at(j, k) - at(j - 1, k)) * (sin_lo * (1 - sin_lo * sin_lo) / rmin);
            }
            // boundary between columns k-1 and k moves in azimuth
            const auto cq = static_cast<size_t>(j * N + kprev);
            float rmin = std::max(near, std::min(R[c], R[cq]));
            if (std::isfinite(rmin) && rmin > 0 && !skip(cq, c)) azim += (at(j, k) - at(j, kprev)) * ((sin_hi - sin_lo) / rmin);
        }
        const float dphi = 2 * kPi / static_cast<float>(N);
        for (size_t ch = 0; ch < C; ++ch) {
            gr[ch] += t_c * chan(rot, static_cast<int>(ch));
            gt[ch] += u_c * (dphi * chan(radial, static_cast<int>(ch))) + t_0 * chan(azim, static_cast<int>(ch));
        }
    }
}

/// The relative standard error of a gather's value `value` (AO, or the irradiance's luminance)
/// from the differences of azimuthally adjacent cells (GatherResult::rel_stderr).
float relative_stderr(const GatherGrid& grid, bool ao, const std::vector<Color>& L, const std::vector<float>& U, double value);
/// The gather's Hessian (hessian.h) from its cells' hits: the radiance `L` (AO mode: the
/// unoccluded fractions `U`) at distances `R` along `D`, escaped rays ending at `far`.
TangentHessian cells_hessian(const GatherGrid& grid, const Vec3& p, const Vec3& n, float far, bool ao, const std::vector<Color>& L,
                             const std::vector<float>& U, const std::vector<float>& R, const std::vector<Vec3>& D, ScratchBuffer& scratch);
/// GatherResult::bins: each bin's mean over the cells whose directions fall in it.
void set_bins(GatherResult& res, const Frame& frame, std::span<const float> ao, const std::vector<Color>& L, const std::vector<Vec3>& D);

}  // namespace bounce
