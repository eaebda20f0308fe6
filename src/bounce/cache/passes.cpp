#include "bounce/cache/passes.h"

#include <tbb/enumerable_thread_specific.h>

#include <algorithm>
#include <cmath>
#include <chrono>
#include <mutex>
#include <shared_mutex>

namespace bounce {

bool SubPass::contains(int x, int y) const {
    if (x % step || y % step) return false;
    int px = (x / step) & 1, py = (y / step) & 1;
    if (!all && (px | (py << 1)) != parity) return false;
    // Quarter classes on the lattice of twice the spacing (for the first level, of the step).
    int q = all ? step : 2 * step;
    return (((x / q) & 1) | (((y / q) & 1) << 1)) == quarter;
}

std::vector<SubPass> subpass_schedule(int first_step) {
    int s = 1;
    while (s * 2 <= first_step) s *= 2;
    std::vector<SubPass> out;
    for (int q = 0; q < 4; ++q) out.push_back({s, 0, true, q});
    for (s /= 2; s >= 1; s /= 2)
        for (int parity : {1, 2, 3})
            for (int q = 0; q < 4; ++q) out.push_back({s, parity, false, q});
    return out;
}

namespace {

/// Where a fragment's records live and the hemisphere its gathers use: the un-displaced
/// surface by default (rays still leave from the displaced point f.p), or the displaced one.
/// Hair: at its strand's root on the growing surface whatever the mode (gather.h hair_site);
/// its gathers leave from there too.
struct Site {
    Vec3 p, n;
    Vec3 origin;      ///< where the gather's rays leave from
    float near = 0;   ///< hits nearer than this do not size the record (Gatherer::gather)
};
Site record_site(const Scene& scene, const Fragment& f, const CacheSettings& cs) {
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

/// The shading-pass interpolation at a fragment: weights at its record site, each record's
/// value extrapolated with its gradients to the fragment's own (displaced) point and normal.
/// Hair gets no gradient along the strand: its value is the one at its site.
Interpolated interpolate_at(const IrradianceCache& cache, const Fragment& f, const Site& site) {
    return f.is_hair() ? cache.lookup(site.p, site.n, true, &site.p, &site.n) : cache.lookup(site.p, site.n, true, &f.p, &f.n);
}

uint64_t candidate_key(const DeepBuffer& deep, int wx, int wy, uint32_t k) {
    uint64_t pix = static_cast<uint64_t>(wy + deep.y0) * static_cast<uint64_t>(deep.full_width) +
                   static_cast<uint64_t>(wx + deep.x0);
    return (pix << 8) | k;
}

enum class Source { Records, Own, Missed };

/// The light at fragment k of window pixel (wx, wy): its own record if per-fragment
/// refinement gave it one, else the interpolation.
Indirect indirect_at(const Scene& scene, const IrradianceCache& cache, const DeepBuffer& deep, int wx, int wy, uint32_t k,
                     Source& src) {
    const Fragment& f = deep.pixel(wx, wy)[k];
    if (cache.fragment_record_count() > 0)
        if (const Record* r = cache.fragment_record(candidate_key(deep, wx, wy, k), f.p)) {
            src = Source::Own;
            return {r->E, r->ao, r->bent, r->dir};
        }
    Interpolated in = interpolate_at(cache, f, record_site(scene, f, cache.settings()));
    src = in.weight > 0 ? Source::Records : Source::Missed;
    return {in.E, in.ao, in.bent, in.dir};
}

/// Takes the cache's lock (shared or exclusive), adding the time waited to `counters`.
template <typename Lock>
Lock lock_cache(const IrradianceCache& cache, Counters& counters) {
    auto t0 = std::chrono::steady_clock::now();
    Lock lock(cache.mutex());
    counters.lock_wait_ns += static_cast<uint64_t>(
        std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() - t0).count());
    return lock;
}

}  // namespace

void gathering_pass(const Scene& scene, const DeepBuffer& deep, const Gatherer& gatherer, IrradianceCache& cache,
                    Stats& stats, ProgressSink* sink, const SubPassCallback& after_subpass, int frame, const Gatherer* first) {
    tbb::enumerable_thread_specific<size_t> full_gathers(0);
    const auto schedule = subpass_schedule(static_cast<int>(cache.settings().max_spacing));
    const bool per_tile = scene.render.parallel.cache_sharing == CacheSharing::PerThread;
    const auto tiles = make_tiles(deep.width, deep.height, scene.render.parallel.tile_size, scene.render.parallel.tile_order);
    Progress progress(sink, "gathering", schedule.size());
    std::vector<std::vector<Record>> made(tiles.size());  // this sub-pass's records, by Tile::index
    size_t dropped = 0, gathered = 0;
    for (size_t si = 0; si < schedule.size(); ++si) {
        const SubPass& sp = schedule[si];
        // 1. Each tile judges its candidates against the cache as it was when the sub-pass
        //    began (shared lock; nobody writes until step 2) and gathers at the misses. In
        //    per-thread mode the tile's own new records count too: they live in the tile's
        //    private cache, which belongs to the thread shading the tile.
        for_each_tile(tiles, [&](const Tile& t) {
            Counters& counters = stats.local();
            auto lock = lock_cache<std::shared_lock<std::shared_mutex>>(cache, counters);
            std::vector<Record>& out = made[static_cast<size_t>(t.index)];
            out.clear();
            for (int wy = t.y0; wy < t.y1; ++wy)
                for (int wx = t.x0; wx < t.x1; ++wx) {
                    if (!sp.contains(wx + deep.x0, wy + deep.y0)) continue;
                    auto frags = deep.pixel(wx, wy);
                    for (uint32_t k = 0; k < frags.size(); ++k) {
                        const Fragment& f = frags[k];
                        const Site site = record_site(scene, f, cache.settings());
                        if (!cache.misses(site.p, site.n, per_tile ? std::span<const Record>(out)
                                                                       : std::span<const Record>())) continue;
                        const RandomStream rng = fragment_stream(scene.render.visibility.seed, wx + deep.x0, wy + deep.y0, k);
                        GatherResult g = first ? first->gather(site.origin, site.n, rng, counters, site.near) : GatherResult{};
                        if (!first || g.rel_stderr > cache.settings().ray_noise) {
                            g = gatherer.gather(site.origin, site.n, rng, counters, site.near);
                            ++full_gathers.local();
                        }
                        Record r = cache.make_record(g, site.p, site.n, f.footprint, candidate_key(deep, wx, wy, k));
                        r.frame = r.gathered = frame;
                        r.origin = site.origin;
                        if (per_tile) {
                            cache.clamp_to_neighbours(r, out);
                            r.support = cache.support(r);
                        }
                        out.push_back(r);
                    }
                }
        });

        // 2. One writer merges, in an order that does not depend on scheduling. Shared: all
        //    records by pixel, dropping those that records inserted before them in this
        //    sub-pass already cover. Per-thread: the tile caches in tile order, all records
        //    kept (each came from one tile's cache, so none is merged twice).
        std::vector<Record> records;
        for (auto& v : made) records.insert(records.end(), v.begin(), v.end());
        gathered += records.size();
        if (!per_tile)
            std::sort(records.begin(), records.end(), [](const Record& a, const Record& b) { return a.key < b.key; });
        auto lock = lock_cache<std::unique_lock<std::shared_mutex>>(cache, stats.local());
        if (cache.luminance_floor() < 0 && !records.empty()) {
            double mean = 0;
            for (const auto& r : records) mean += luminance(r.E);
            cache.set_luminance_floor(static_cast<float>(1e-3 * mean / static_cast<double>(records.size())));
        }
        size_t before = cache.size();
        for (auto& r : records) {
            if (!per_tile && cache.size() > before && !cache.misses(r.p, r.n)) {
                ++dropped;
                continue;
            }
            cache.insert(r);
        }
        lock.unlock();
        progress.add();
        if (after_subpass) after_subpass(sp, si, schedule.size());
    }
    stats.set("records", static_cast<double>(cache.size()));
    stats.set("record_gathers", static_cast<double>(gathered));
    if (first) {
        size_t full = 0;
        for (size_t n : full_gathers) full += n;
        stats.set("record_gathers_full_rays", static_cast<double>(full));
        stats.set("record_first_rays", static_cast<double>(first->grid().rays()));
    }
    stats.set("records_dropped", static_cast<double>(dropped));
    stats.set("subpasses", static_cast<double>(schedule.size()));
    stats.set("rays_per_gather", gathered ? static_cast<double>(stats.total().gather_rays) / static_cast<double>(gathered) : 0.0);
    stats.set("cache_bytes", static_cast<double>(cache.memory_bytes()));
}

bool refinement_runs(const Scene& scene) {
    const CacheSettings& cs = scene.render.cache;
    if (cs.refine > 0) return true;
    if (cs.refine_tilt <= 0 || cs.displaced_records != RecordSurface::Undisplaced) return false;
    return std::any_of(scene.objects.begin(), scene.objects.end(), [](const Object& o) { return o.displacement_bound > 0; });
}

size_t refinement_pass(const Scene& scene, const DeepBuffer& deep, const Gatherer& refiner, IrradianceCache& cache,
                       Stats& stats, ProgressSink* sink, int frame) {
    const CacheSettings& cs = cache.settings();
    const float threshold = cs.refine;
    const bool tilt_signal = cs.displaced_records == RecordSurface::Undisplaced && cs.refine_tilt > 0;
    const float tilt_cos = std::cos(cs.refine_tilt * kPi / 180);
    tbb::enumerable_thread_specific<std::vector<Record>> made;
    {
        // Lookups only: nobody inserts until every fragment is judged, so the decision sees the
        // finished cache whatever the thread count.
        auto lock = lock_cache<std::shared_lock<std::shared_mutex>>(cache, stats.local());
        for_each_pixel_in_tiles(deep, scene.render.parallel.tile_size, sink, "refining", [&](int wx, int wy, size_t) {
            auto frags = deep.pixel(wx, wy);
            for (uint32_t k = 0; k < frags.size(); ++k) {
                const Fragment& f = frags[k];
                if (f.is_hair()) continue;  // hair keeps its strand's value (no fragment gathers)
                const uint64_t key = candidate_key(deep, wx, wy, k);
                if (cache.fragment_record(key, f.p)) continue;  // refined by an earlier render
                // Interpolation about the un-displaced normal cannot stand for a hemisphere
                // tilted far from it (docs/displacement.md): those fragments gather their own.
                const bool tilted = tilt_signal && dot(f.n, f.n_base) < tilt_cos;
                if (!tilted) {
                    const Interpolated in = interpolate_at(cache, f, record_site(scene, f, cs));
                    if (in.weight > 0 && (threshold <= 0 || in.spread <= threshold)) continue;
                }
                // Gathered about the fragment's own (displaced) point and normal, as brute force does.
                const GatherResult g = refiner.gather(
                    f.p, f.n, fragment_stream(scene.render.visibility.seed, wx + deep.x0, wy + deep.y0, k), stats.local());
                Record r;
                r.p = f.p, r.n = f.n, r.E = g.irradiance, r.ao = g.ao, r.bent = g.bent_normal, r.dir = g.light_dir;
                // Never used for reach; positive so the record is a valid one in a cache file.
                r.footprint = f.footprint > 0 ? f.footprint : 1e-6f;
                r.radius = r.raw_radius = r.footprint;
                r.harmonic = g.harmonic_distance, r.dmin = g.min_distance;
                r.key = key, r.rays = static_cast<uint32_t>(g.rays), r.frame = r.gathered = frame;
                r.origin = f.p;
                made.local().push_back(r);
            }
        }, scene.render.parallel.tile_order);
    }
    std::vector<Record> records;
    for (auto& v : made) records.insert(records.end(), v.begin(), v.end());
    std::sort(records.begin(), records.end(), [](const Record& a, const Record& b) { return a.key < b.key; });
    auto lock = lock_cache<std::unique_lock<std::shared_mutex>>(cache, stats.local());
    for (const Record& r : records) cache.insert_fragment_record(r);
    stats.set("refined_fragments", static_cast<double>(records.size()));
    stats.set("refine_rays_per_gather", static_cast<double>(refiner.grid().rays()));
    return records.size();
}

InterpolatedLight interpolation_pass(const Scene& scene, const DeepBuffer& deep, const IrradianceCache& cache,
                                     Stats& stats, ProgressSink* sink) {
    InterpolatedLight out;
    out.light.resize(deep.fragments.size());
    out.refined.assign(deep.fragments.size(), 0);
    tbb::enumerable_thread_specific<uint64_t> misses(0), lookups(0), own(0);
    // The pass holds the shared lock for its workers: no writer can interleave.
    auto lock = lock_cache<std::shared_lock<std::shared_mutex>>(cache, stats.local());
    for_each_pixel_in_tiles(deep, scene.render.parallel.tile_size, sink, "interpolate", [&](int wx, int wy, size_t first) {
        auto frags = deep.pixel(wx, wy);
        for (uint32_t k = 0; k < frags.size(); ++k) {
            Source src;
            out.light[first + k] = indirect_at(scene, cache, deep, wx, wy, k, src);
            ++lookups.local();
            if (src == Source::Own) {
                ++own.local();
                out.refined[first + k] = 1;
            }
            misses.local() += src == Source::Missed;
        }
    }, scene.render.parallel.tile_order);
    uint64_t m = 0, l = 0, o = 0;
    for (auto v : misses) m += v;
    for (auto v : lookups) l += v;
    for (auto v : own) o += v;
    stats.set("shading_misses", static_cast<double>(m));
    stats.set("lookups", static_cast<double>(l));
    stats.set("fragment_records_used", static_cast<double>(o));
    out.misses = static_cast<size_t>(m);
    return out;
}

/// Preview: each pixel takes the indirect light of the nearest pixel (on the lattices of the
/// current step, then coarser ones) that a finished sub-pass visited.
std::vector<Indirect> preview_indirect(const Scene& scene, const DeepBuffer& deep, const IrradianceCache& cache,
                                       const std::vector<uint8_t>& visited, int step) {
    std::vector<Indirect> out(deep.fragments.size());
    parallel_for_each_index(0, deep.height, [&](int wy) {
        for (int wx = 0; wx < deep.width; ++wx) {
            int x = wx + deep.x0, y = wy + deep.y0, lx = wx, ly = wy;
            for (int s = step; s <= (1 << 20); s *= 2) {
                int cx = x - x % s - deep.x0, cy = y - y % s - deep.y0;
                if (cx >= 0 && cy >= 0 && visited[static_cast<size_t>(cy) * deep.width + cx]) {
                    lx = cx, ly = cy;
                    break;
                }
            }
            if (deep.pixel(lx, ly).empty()) lx = wx, ly = wy;
            size_t first = deep.offsets[static_cast<size_t>(wy) * deep.width + wx];
            auto frags = deep.pixel(wx, wy);
            const auto n = static_cast<uint32_t>(deep.pixel(lx, ly).size());
            Source unused;
            for (uint32_t k = 0; k < frags.size(); ++k) out[first + k] = indirect_at(scene, cache, deep, lx, ly, std::min(k, n - 1), unused);
        }
    });
    return out;
}

}  // namespace bounce
