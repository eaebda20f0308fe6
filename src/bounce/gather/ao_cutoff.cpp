#include "bounce/gather/ao_cutoff.h"

#include <algorithm>
#include <cmath>

namespace bounce::detail {

namespace {

bool hits(const CutoffCells& c, size_t i) { return std::isfinite(c.R[i]) && dot(c.NH[i], c.NH[i]) > 0; }

bool on_one_surface(const CutoffCells& c, size_t a, size_t b) {
    if (!hits(c, a) || !hits(c, b)) return false;
    const Vec3 d = c.D[b] * c.R[b] - c.D[a] * c.R[a];  // between the hits
    const float tol = 0.1f * length(d) + 1e-6f * (c.R[a] + c.R[b]);
    return std::abs(dot(c.NH[a], d)) <= tol && std::abs(dot(c.NH[b], d)) <= tol;
}

/// d t / d x for cell i: the hit's distance along its fixed direction as the gather point moves
/// (a plane n.(y - x) = 0 along D: t = n.(y - x) / n.D), grazing hits limited.
Vec3 distance_rate(const CutoffCells& c, size_t i) {
    const Vec3& n = c.NH[i];
    float nd = dot(n, c.D[i]);
    nd = std::copysign(std::max(std::abs(nd), 0.05f), nd);
    return n * (-1.0f / nd);
}

}  // namespace

SurfacePairs::SurfacePairs(const GatherGrid& grid, const CutoffCells& cells)
    : grid_(grid), cells_(cells), next_k_(static_cast<size_t>(grid.rays()), -1), next_j_(static_cast<size_t>(grid.rays()), -1) {}

bool SurfacePairs::next(size_t c, bool radial) const {
    int8_t& known = radial ? next_j_[c] : next_k_[c];
    if (known < 0) {
        const auto n = static_cast<size_t>(grid_.n);
        const size_t j = c / n, k = c % n;
        known = radial ? (j + 1 < static_cast<size_t>(grid_.m) && on_one_surface(cells_, c, c + n))
                       : on_one_surface(cells_, c, j * n + (k + 1) % n);
    }
    return known;
}

bool SurfacePairs::operator()(size_t a, size_t b) const {
    if (a > b) std::swap(a, b);
    const auto n = static_cast<size_t>(grid_.n);
    if (b - a == n) return next(a, true);
    if (b - a == 1 && b % n != 0) return next(a, false);
    return a % n == 0 && b == a + n - 1 && next(b, false);  // the seam: k = n - 1 and k = 0
}

float SurfacePairs::step(int j, int k, bool radial) const {
    const size_t a = cell(j, k), b = radial ? cell(j + 1, k) : cell(j, k + 1);
    return next(a, radial) ? cells_.R[b] - cells_.R[a] : 0.0f;
}

Vec3 SurfacePairs::gradient() const {
    const int M = grid_.m;
    // The distance's change per cell step at cell (j, k), radially and in azimuth: the mean of
    // its two steps on one surface.
    const auto radial_rate = [&](int j, int k) {
        return 0.5f * ((j > 0 ? step(j - 1, k, true) : 0.0f) + (j + 1 < M ? step(j, k, true) : 0.0f));
    };
    const auto azimuthal_rate = [&](int j, int k) { return 0.5f * (step(j, k - 1, false) + step(j, k, false)); };
    Vec3 g(0);
    // The pair of cell (j, k) and its next one, with the distance's rate `along` it (0: not one
    // surface, or no change) and `across` it: (U_b - U_a) along / (along^2 + across^2) times g.
    const auto add = [&](int j, int k, bool radial, const auto& across) {
        const size_t a = cell(j, k), b = radial ? cell(j + 1, k) : cell(j, k + 1);
        const CutoffCells& c = cells_;
        if (c.U[a] == c.U[b]) return;
        const float along = step(j, k, radial);
        if (along == 0) return;
        const float rate = across();
        g += (distance_rate(c, a) + distance_rate(c, b)) * (0.5f * (c.U[b] - c.U[a]) * along / (along * along + rate * rate));
    };
    for (int j = 0; j < M; ++j)
        for (int k = 0; k < grid_.n; ++k) {
            add(j, k, false, [&] { return 0.5f * (radial_rate(j, k) + radial_rate(j, k + 1)); });
            if (j + 1 < M) add(j, k, true, [&] { return 0.5f * (azimuthal_rate(j, k) + azimuthal_rate(j + 1, k)); });
        }
    return g / static_cast<float>(grid_.rays());
}

}  // namespace bounce::detail
