#include "bounce/gather/guide.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include <optional>

#include "bounce/core/parallel.h"
#include "bounce/gather/gather_cells.h"

namespace bounce {

std::array<int, kReachBins> guided_allocation(const DirectionGuide& guide, int rays, float share) {
    std::array<int, kReachBins> out{};
    if (rays < kReachBins) {  // fewer rays than bins: no bin may go without, so no guide
        for (int i = 0; i < rays; ++i) ++out[static_cast<size_t>(i * kReachBins / std::max(1, rays))];
        return out;
    }
    double total = 0;
    for (float s : guide.spread) total += std::isfinite(s) && s > 0 ? s : 0;
    const double guided = total > 0 ? std::clamp(static_cast<double>(share), 0.0, 1.0) : 0.0;
    // One ray per bin first (unbiased needs every bin sampled), the rest by the mixture.
    const int rest = rays - kReachBins;
    std::array<double, kReachBins> want{};
    int given = 0;
    for (size_t b = 0; b < want.size(); ++b) {
        const double s = std::isfinite(guide.spread[b]) && guide.spread[b] > 0 ? guide.spread[b] : 0.0;
        want[b] = rest * ((1 - guided) / kReachBins + (guided > 0 ? guided * s / total : 0.0));
        out[b] = 1 + static_cast<int>(want[b]);
        given += out[b];
    }
    // Largest remainders, ties to the lower bin: the same guide always gives the same split.
    std::array<size_t, kReachBins> order{};
    std::iota(order.begin(), order.end(), size_t{0});
    std::stable_sort(order.begin(), order.end(),
                     [&](size_t a, size_t b) { return want[a] - std::floor(want[a]) > want[b] - std::floor(want[b]); });
    for (size_t i = 0; given < rays; ++i, ++given) ++out[order[i % order.size()]];
    return out;
}

void guided_rays(const std::array<int, kReachBins>& allocation, const RandomStream& rng, GuidedRays& out) {
    out.local.clear(), out.weight.clear();
    uint64_t i = 0;
    for (int b = 0; b < kReachBins; ++b) {
        const int count = allocation[static_cast<size_t>(b)];
        if (count <= 0) continue;
        const int band = b / kReachSectors, sector = b % kReachSectors;
        // A bin spans 1/4 in sin^2 and 2 pi / 8 in azimuth: rows x columns cells about twice
        // as wide in phi as tall in sin^2, as the gather's own grid; rows take their share of
        // the bin's rays (the first `extra` one more), each row stratified in azimuth.
        const int rows = std::clamp(static_cast<int>(std::lround(std::sqrt(count / 1.57))), 1, count);
        const int per_row = count / rows, extra = count % rows;
        for (int r = 0; r < rows; ++r) {
            const int cols = per_row + (r < extra ? 1 : 0);
            const float w = 1.0f / (kReachBins * static_cast<float>(rows) * static_cast<float>(cols));
            const GatherGrid sub{kReachBands * rows, kReachSectors * cols};
            for (int k = 0; k < cols; ++k, ++i) {
                out.local.push_back(
                    gather_cell_direction(sub, band * rows + r, sector * cols + k, rng.get(i, kDimGather), rng.get(i, kDimGather + 1)));
                out.weight.push_back(w);
            }
        }
    }
}

DirectionGuide Gatherer::pilot(const Vec3& p, const Vec3& n, const RandomStream& rng, Counters& counters) const {
    gather(p, n, rng, counters);
    return cells_guide(scratch(), n);  // the cells that gather left
}

DirectionGuide Gatherer::cells_guide(const detail::Cells& cells, const Vec3& n) const {
    // Neighbouring cells of a row within one bin: each pair's squared difference estimates twice
    // the variance a stratified ray meets there (smooth change within the bin costs little).
    DirectionGuide guide;
    guide.n = n;
    std::array<double, kReachBins> d2{};
    std::array<int, kReachBins> pairs{};
    const int M = grid_.m, N = grid_.n;
    const auto value = [&](int j, int k) {
        const auto c = static_cast<size_t>(j * N + k);
        return settings_.ao ? static_cast<double>(cells.U[c]) : static_cast<double>(luminance(cells.L[c]));
    };
    for (int j = 0; j < M; ++j)
        for (int k = 0; k + 1 < N; ++k) {
            const int bin = (j * kReachBands / M) * kReachSectors + k * kReachSectors / N;
            if (bin != (j * kReachBands / M) * kReachSectors + (k + 1) * kReachSectors / N) continue;
            const double d = value(j, k) - value(j, k + 1);
            d2[static_cast<size_t>(bin)] += d * d, ++pairs[static_cast<size_t>(bin)];
        }
    for (size_t b = 0; b < guide.spread.size(); ++b)
        guide.spread[b] = pairs[b] ? static_cast<float>(std::sqrt(0.5 * d2[b] / pairs[b])) : 0.0f;
    return guide;
}

GatherResult Gatherer::gather_guided(const Vec3& p, const Vec3& n, const RandomStream& rng, const DirectionGuide& guide,
                                     Counters& counters) const {
    if (lights_) return gather(p, n, rng, counters);  // per-light parts are sums over the grid's cells
    if (settings_.cancel) settings_.cancel->check();
    detail::Cells& cells = scratch();
    GuidedRays& rays = cells.guided;
    guided_rays(guided_allocation(guide, grid_.rays(), settings_.guided), rng, rays);
    const size_t S = rays.local.size();
    const Frame frame(n);
    cells.resize(S);
    for (size_t c = 0; c < S; ++c) cells.D[c] = frame.to_world(rays.local[c]), cells.cos_theta[c] = rays.local[c].z;
    accel_.trace_many(p, cells.D, cells.hits);  // bin by bin: neighbouring directions already
    counters.gather_rays += static_cast<uint64_t>(S);
    GatherResult res;
    res.rays = static_cast<int>(S);
    Vec3 sum_u_dir(0);
    float sum_u = 0;
    double inv_r = 0;
    for (size_t c = 0; c < S; ++c) {
        const float w = rays.weight[c];
        const Hit& h = cells.hits[c];
        const Color l = cell_radiance(cells, p, c, rng, counters, {}) * w;
        const float u = h.valid() ? unoccluded(h.t) * w : w;
        if (h.valid()) inv_r += w / std::max(h.t, 1e-20f);
        res.irradiance += l;
        for (int ch = 0; ch < 3; ++ch) res.light_dir[static_cast<size_t>(ch)] += cells.D[c] * l[ch];
        sum_u += u, sum_u_dir += cells.D[c] * u;
    }
    res.irradiance = res.irradiance * kPi;
    for (Vec3& d : res.light_dir) d = d * kPi;
    res.ao = sum_u;
    res.harmonic_distance = inv_r > 0 ? static_cast<float>(1 / inv_r) : INFINITY;
    res.bent_normal = dot(sum_u_dir, sum_u_dir) > 0 ? normalize(sum_u_dir) : n;
    return res;
}

namespace {

/// The site of the first fragment of full-image pixel (x, y) that takes bounce light, and its index.
std::optional<std::pair<HairSite, uint32_t>> first_site(const Scene& scene, const DeepBuffer& deep, int x, int y) {
    const auto frags = deep.pixel(x - deep.x0, y - deep.y0);
    for (uint32_t k = 0; k < frags.size(); ++k)
        if (needs_bounce_light(scene, frags[k])) return std::pair{gather_site(scene, frags[k]), k};
    return std::nullopt;
}

/// The pilots of a window's blocks, which sit on the full image's grid of kGuideBlock pixels,
/// so a window (a tile of another rank, a crop) finds the pilots the whole image would where its
/// edges follow the grid: each block's centre pixel, clamped into the window. A block whose
/// centre pixel takes no bounce light has none.
class Pilots {
  public:
    Pilots(const Scene& scene, const DeepBuffer& deep, const Gatherer& gatherer, Stats& stats)
        : bx0_(deep.x0 / kGuideBlock), by0_(deep.y0 / kGuideBlock), bw_(blocks(deep.x0, deep.width)) {
        guides_.resize(static_cast<size_t>(bw_) * static_cast<size_t>(blocks(deep.y0, deep.height)));
        const uint64_t seed = hash_combine(gatherer.settings().tiling.seed, 0x9170e5ULL);  // the pilots' own streams
        // At least kPilotRays, so that each bin's spread rests on a few dozen cells.
        const Gatherer pilot = gatherer.with_rays(std::max(gatherer.grid().rays(), kPilotRays));
        parallel_for_each_index(size_t{0}, guides_.size(), [&](size_t i) {
            const int bx = bx0_ + static_cast<int>(i % static_cast<size_t>(bw_)),
                      by = by0_ + static_cast<int>(i / static_cast<size_t>(bw_));
            const int x = std::clamp(bx * kGuideBlock + kGuideBlock / 2, deep.x0, deep.x0 + deep.width - 1);
            const int y = std::clamp(by * kGuideBlock + kGuideBlock / 2, deep.y0, deep.y0 + deep.height - 1);
            if (const auto site = first_site(scene, deep, x, y))
                guides_[i] = pilot.pilot(site->first.p, site->first.n, fragment_stream(seed, x, y, site->second), stats.local());
        });
    }
    /// The guide of full-image pixel (x, y)'s block (null: its pilot was not made).
    const DirectionGuide* at(int x, int y) const {
        const auto& g =
            guides_[static_cast<size_t>(y / kGuideBlock - by0_) * static_cast<size_t>(bw_) + static_cast<size_t>(x / kGuideBlock - bx0_)];
        return g ? &*g : nullptr;
    }

  private:
    /// Blocks over [from, from + size) pixels.
    static int blocks(int from, int size) { return size > 0 ? (from + size - 1) / kGuideBlock - from / kGuideBlock + 1 : 0; }
    int bx0_, by0_, bw_;
    std::vector<std::optional<DirectionGuide>> guides_;
};

}  // namespace

std::vector<Indirect> gather_every_fragment(const Scene& scene, const DeepBuffer& deep, const Gatherer& gatherer, Stats& stats,
                                            ProgressSink* sink) {
    const std::optional<Pilots> pilots =
        gatherer.settings().guided > 0 ? std::optional<Pilots>(std::in_place, scene, deep, gatherer, stats) : std::nullopt;
    std::vector<Indirect> out(deep.fragments.size());
    // The true surface: the displaced point and normal (the cache's un-displaced hemisphere is
    // its approximation, measured against this). Hair: its site.
    for_each_bounce_fragment(scene, deep, gatherer.settings().tiling, sink, "gather", [&](const BounceFragment& b) {
        Counters& counters = stats.local();
        const DirectionGuide* guide = pilots ? pilots->at(deep.x0 + b.wx, deep.y0 + b.wy) : nullptr;
        const GatherResult g = guide && dot(guide->n, b.site.n) >= kGuideCos
                                   ? gatherer.gather_guided(b.site.p, b.site.n, b.rng, *guide, counters)
                                   : gatherer.gather(b.site.p, b.site.n, b.rng, counters);
        out[b.index] = {g.irradiance, g.ao, g.bent_normal, g.light_dir};
        if (takes_back_light(scene, b.f, gatherer.settings().ao))  // a plain gather: the pilots guide the front side's
            out[b.index].back = gatherer.gather(b.site.p, -b.site.n, back_side_stream(b.rng), counters).irradiance;
    });
    return out;
}

}  // namespace bounce
