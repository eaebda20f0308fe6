// What the cache's passes share (internal to cache/): where a fragment's records live, the
// creation key of a fragment's record, and taking the cache's lock with the wait counted.
#pragma once

#include <chrono>
#include <cstdint>
#include <utility>

#include "bounce/cache/irradiance_cache.h"
#include "bounce/core/stats.h"
#include "bounce/deep/deep_buffer.h"
#include "bounce/gather/gather.h"

namespace bounce {

/// The hemisphere of a fragment a record serves: a thin translucent surface's fragments take
/// bounce light through both (takes_back_light), each side from records of its own; the back
/// side's records lie at the same point about the reversed normal (docs/shading.md).
enum class Side : uint8_t { Front, Back };

/// Where a fragment's records live and the hemisphere its gathers use: the un-displaced
/// surface by default (rays still leave from the displaced point f.p), or the displaced one.
/// Hair: at its strand's root on the growing surface whatever the mode (gather.h hair_site);
/// its gathers leave from there too.
struct Site {
    Vec3 p, n;
    Vec3 origin;     ///< where the gather's rays leave from
    float near = 0;  ///< hits nearer than this do not size the record (Gatherer::gather)
};
inline Site record_site(const Scene& scene, const Fragment& f, const CacheSettings& cs, Side side = Side::Front) {
    if (side == Side::Back) {
        Site s = record_site(scene, f, cs);
        s.n = -s.n;
        return s;
    }
    if (f.is_hair()) {
        const HairSite h = hair_site(scene, f);
        return {h.p, h.n, h.p};
    }
    if (cs.displaced_records == RecordSurface::Displaced) return {f.p, f.n, f.p};
    // The displacement's own bumps are what the un-displaced surface leaves out: they shade the
    // record's value but do not shrink its reach (docs/displacement.md).
    const float near = cs.displacement_near * scene.objects[f.object].displacement_bound;
    return {f.p_base, f.n_base, f.p, near};
}

/// The point and normal the shading pass extrapolates a fragment's records to: its own
/// (displaced) point and normal; hair gets no gradient along the strand (its site's).
/// (The back side's: the same point about the reversed normal.)
inline std::pair<Vec3, Vec3> extrapolated_to(const Fragment& f, const Site& site, Side side) {
    if (f.is_hair()) return {site.p, site.n};
    return {f.p, side == Side::Back ? -f.n : f.n};
}

/// The shading-pass interpolation at a fragment's side: weights at its record site, each
/// record's value extrapolated with its gradients to extrapolated_to.
inline Interpolated interpolate_at(const IrradianceCache& cache, const Fragment& f, const Site& site, Side side = Side::Front) {
    const auto [p, n] = extrapolated_to(f, site, side);
    return cache.lookup(site.p, site.n, true, &p, &n);
}

/// Each light's share of interpolate_at's value (IrradianceCache::light_shares), into `out`.
inline void light_shares_at(const IrradianceCache& cache, const Fragment& f, const Site& site, std::span<Color> out,
                            Side side = Side::Front) {
    const auto [p, n] = extrapolated_to(f, site, side);
    cache.light_shares(site.p, site.n, true, &p, &n, out);
}

/// A back side's record key: its front's with the top bit set (no image is 2^55 pixels).
inline constexpr uint64_t kBackSideKey = uint64_t{1} << 63;

inline uint64_t candidate_key(const DeepBuffer& deep, int wx, int wy, uint32_t k, Side side = Side::Front) {
    uint64_t pix = static_cast<uint64_t>(wy + deep.y0) * static_cast<uint64_t>(deep.full_width) + static_cast<uint64_t>(wx + deep.x0);
    return (pix << 8) | k | (side == Side::Back ? kBackSideKey : 0);
}

/// Takes the cache's lock (shared or exclusive), adding the time waited to `counters`.
template <typename Lock>
Lock lock_cache(const IrradianceCache& cache, Counters& counters) {
    auto t0 = std::chrono::steady_clock::now();
    Lock lock(cache.mutex());
    counters.lock_wait_ns +=
        static_cast<uint64_t>(std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() - t0).count());
    return lock;
}

}  // namespace bounce
