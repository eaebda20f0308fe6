// Gatherer::reproject: a gather made mostly of a nearby earlier gather's rays (docs/animation.md,
// "refinement in frames of a shot"). p's hemisphere splits in two:
//  - cells traced again: those of the earlier gather whose rays met something nearer than
//    `near` = kReprojectNear |p - p'| to p' (or fur), widened by 1.5 / kReprojectNear radians,
//    more than a far point moves between the two views. They are traced from p; all they meet
//    counts.
//  - the rest, from the earlier gather's far hits and escaped rays. It sampled a hit x with
//    density cos(theta') cos(theta_x') / (pi r'^2) per area at x; seen from p, x carries
//    cos(theta) cos(theta_x) / r^2 of the integrand: each far hit whose direction from p falls
//    outside the cells traced again counts with the ratio of the two (0 where p sees x from
//    behind or below its horizon). It assumes p sees what p' saw there: the cells traced again
//    hold the silhouettes of what is near, where that could fail.
#include "bounce/gather/gather.h"

#include "bounce/gather/gather_cells.h"

namespace bounce {

namespace {

/// The largest ratio of densities a far hit may carry (a hit seen edge-on from p'): bounds the
/// variance one cell can add, at the cost of a little of that hit's light.
constexpr float kMaxWeight = 8;

}  // namespace

namespace detail {

/// Per cell, the cells within `margin` radians of it (any of their directions, from the
/// cells' centres and widths), itself included. Local to the grid, so shared by all gathers.
std::vector<std::vector<uint32_t>> cell_margins(const GatherGrid& grid, float margin) {
    const auto S = static_cast<size_t>(grid.rays());
    std::vector<Vec3> centre(S);
    std::vector<float> width(S);  // from the centre to the farthest corner, radians
    for (int j = 0; j < grid.m; ++j)
        for (int k = 0; k < grid.n; ++k) {
            const auto c = static_cast<size_t>(j * grid.n + k);
            centre[c] = gather_cell_direction(grid, j, k, 0.5f, 0.5f);
            for (float u : {0.0f, 1.0f})
                for (float v : {0.0f, 1.0f}) {
                    const float cosine = std::clamp(dot(centre[c], gather_cell_direction(grid, j, k, u, v)), -1.0f, 1.0f);
                    width[c] = std::max(width[c], std::acos(cosine));
                }
        }
    std::vector<std::vector<uint32_t>> out(S);
    for (size_t a = 0; a < S; ++a)
        for (size_t b = 0; b < S; ++b)
            if (std::acos(std::clamp(dot(centre[a], centre[b]), -1.0f, 1.0f)) <= margin + width[a] + width[b])
                out[a].push_back(static_cast<uint32_t>(b));
    return out;
}

}  // namespace detail

namespace {

/// The cell of `grid` that local direction `d` (z: the normal; above the horizon) falls in
/// (gather_cell_direction's inverse).
size_t cell_of(const GatherGrid& grid, const Vec3& d) {
    const float sin2 = std::max(0.0f, 1 - d.z * d.z);
    float phi = std::atan2(d.y, d.x);
    if (phi < 0) phi += 2 * kPi;
    const int j = std::min(grid.m - 1, static_cast<int>(sin2 * static_cast<float>(grid.m)));
    const int k = std::min(grid.n - 1, static_cast<int>(phi / (2 * kPi) * static_cast<float>(grid.n)));
    return static_cast<size_t>(j * grid.n + k);
}

/// The sums of a gather, each sample weighted.
struct Sums {
    Color E{0};
    std::array<Vec3, 3> dir{};
    double u = 0;
    Vec3 u_dir{0};
    void add(const Vec3& d, const Color& L, float u_share, float w) {
        E += L * w;
        for (int ch = 0; ch < 3; ++ch) dir[static_cast<size_t>(ch)] += d * (L[ch] * w);
        u += u_share * w;
        u_dir += d * (u_share * w);
    }
};

}  // namespace

GatherResult Gatherer::reproject(const Vec3& p, const Vec3& n, const RandomStream& rng, const EarlierGather& from,
                                 Counters& counters) const {
    if (settings_.cancel) settings_.cancel->check();
    const GatherHits& kept = from.hits;
    const auto S = static_cast<size_t>(grid_.rays());
    if (kept.t.size() != S || kept.m != grid_.m || lights_) return gather(p, n, rng, counters);
    const float near = kReprojectNear * length(p - from.p);
    // What a ray brings, as finish() shades it (AO mode: nothing; occlusion alone).
    const auto radiance = [&](const Hit& h, const SurfacePoint* sp, const Vec3& d, uint64_t ray) {
        if (settings_.ao) return Color(0);
        if (!h.valid()) return escaped_radiance(d, {});
        if (h.hair) return hair_radiance(h, p + d * h.t, d, rng, ray, counters, {});
        return hit_radiance(h, sp ? *sp : scene_.objects[h.object].coarse_point(h.prim, h.u, h.v), d, rng, ray, counters, {});
    };
    Sums sums;
    // Cells of p's gather traced again: those about the earlier gather's near hits, widened.
    detail::Cells& cells = scratch();
    const auto scope = cells.scratch.scope();
    const std::span<uint8_t> again = cells.scratch.take<uint8_t>(S, 0);
    const auto& around = reprojection_margins();
    for (size_t c = 0; c < S; ++c)
        if (kept.object[c] != kNoHit && ((kept.object[c] & GatherHits::kHairBit) || kept.t[c] < near))
            for (uint32_t b : around[c]) again[b] = 1;
    // The other directions from the earlier gather's far hits (its directions about its own
    // normal), each where p sees it, if that is not a cell traced again.
    cell_directions(cells, from.n, from.rng);
    const Frame frame(n);
    const auto traced_again = [&](const Vec3& d) { return again[cell_of(grid_, frame.to_local(d))] != 0; };
    for (size_t c = 0; c < S; ++c) {
        const uint32_t object = kept.object[c];
        const float cos_then = std::max(cells.cos_theta[c], 1e-6f);
        if (object == kNoHit) {  // the sky, along the same direction
            const Vec3& d = cells.D[c];
            const float cos_now = dot(d, n);
            if (cos_now > 0 && !traced_again(d)) sums.add(d, radiance(Hit{}, nullptr, d, c), 1, std::min(cos_now / cos_then, kMaxWeight));
            continue;
        }
        if ((object & GatherHits::kHairBit) || kept.t[c] < near) continue;
        const SurfacePoint sp = scene_.objects[object].coarse_point(kept.prim[c], kept.u[c], kept.v[c]);
        const Vec3 to = sp.p - p;
        const float r = length(to);
        const Vec3 d = to / r;
        const float cos_now = dot(d, n), cos_x_now = dot(sp.ng, d), cos_x_then = dot(sp.ng, cells.D[c]);
        if (cos_now <= 0 || (cos_x_now > 0) != (cos_x_then > 0)) continue;  // p cannot see it
        if (traced_again(d)) continue;
        const float t = kept.t[c];
        const float w =
            std::min(cos_now * std::abs(cos_x_now) * t * t / std::max(cos_then * std::abs(cos_x_then) * r * r, 1e-20f), kMaxWeight);
        const Hit h{r, object, kept.prim[c], kept.u[c], kept.v[c], false};
        sums.add(d, radiance(h, &sp, d, c), unoccluded(r), w);
    }
    // The cells traced again, from p: all they meet counts.
    cell_directions(cells, n, rng);
    size_t count = 0;
    for (size_t c = 0; c < S; ++c) count += again[c];
    const std::span<uint32_t> ids = cells.scratch.take<uint32_t>(count);
    const std::span<Vec3> dirs = cells.scratch.take<Vec3>(count);
    const std::span<Hit> traced = cells.scratch.take<Hit>(count);
    for (size_t c = 0, i = 0; c < S; ++c)
        if (again[c]) ids[i] = static_cast<uint32_t>(c), dirs[i++] = cells.D[c];
    accel_.trace_many(p, dirs, traced);
    counters.gather_rays += dirs.size();
    for (size_t i = 0; i < ids.size(); ++i) {
        const Hit& h = traced[i];
        sums.add(dirs[i], radiance(h, nullptr, dirs[i], ids[i]), h.valid() ? unoccluded(h.t) : 1, 1);
    }
    GatherResult res;
    const float scale = kPi / static_cast<float>(S);
    res.irradiance = sums.E * scale;
    for (size_t ch = 0; ch < 3; ++ch) res.light_dir[ch] = sums.dir[ch] * scale;
    res.ao = static_cast<float>(sums.u / static_cast<double>(S));
    res.bent_normal = dot(sums.u_dir, sums.u_dir) > 0 ? normalize(sums.u_dir) : n;
    res.rays = static_cast<int>(ids.size());
    return res;
}

}  // namespace bounce
