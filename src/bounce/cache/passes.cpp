#include "bounce/cache/passes.h"

#include "bounce/cache/cache_file.h"
#include "bounce/cache/control_variate.h"
#include "bounce/cache/sites.h"
#include "bounce/cache/temporal.h"

#include <tbb/enumerable_thread_specific.h>

#include <algorithm>
#include <cmath>
#include <chrono>
#include <cstring>
#include <mutex>
#include <stdexcept>
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

enum class Source { Records, Own, Missed };

/// Interpolation about the un-displaced normal cannot stand for a hemisphere tilted far from it
/// (docs/displacement.md): such fragments gather their own, whatever their records say.
bool tilted_off_records(const CacheSettings& cs, const Fragment& f) {
    return cs.displaced_records == RecordSurface::Undisplaced && cs.refine_tilt > 0 &&
           dot(f.n, f.n_base) < std::cos(cs.refine_tilt * kPi / 180);
}

/// How much of a refined fragment's own gather it shows (CacheSettings::refine_band): all of it
/// where no record applies, its normal tilts off the records', or they disagree by refine_band x
/// refine; in proportion between refine and that, so that crossing the threshold is gradual.
float own_share(const CacheSettings& cs, const Fragment& f, const Interpolated& in) {
    if (cs.refine_band <= 1 || cs.refine <= 0 || in.weight <= 0 || tilted_off_records(cs, f)) return 1;
    return std::clamp((in.spread - cs.refine) / ((cs.refine_band - 1) * cs.refine), 0.0f, 1.0f);
}

/// Where a fragment's light came from: the records, its own gather (`record`; `own` of it, the
/// rest the interpolation's `interpolated`) or nowhere.
struct Origin {
    Source src = Source::Records;
    float own = 0;
    const Record* record = nullptr;
    Color interpolated;
    bool back_missed = false;  ///< a translucent fragment's back side found no record
};

/// The light at fragment k of window pixel (wx, wy) through its front: its own record if
/// per-fragment refinement gave it one (blended with the interpolation inside the refine
/// band), else the interpolation.
Indirect front_indirect_at(const Scene& scene, const IrradianceCache& cache, const DeepBuffer& deep, int wx, int wy, uint32_t k,
                           Origin& from) {
    const Fragment& f = deep.pixel(wx, wy)[k];
    from = {};
    if (!needs_bounce_light(scene, f)) return {};  // nothing to look up: not a miss
    const CacheSettings& cs = cache.settings();
    const Record* r = cache.fragment_record_count() > 0 ? cache.fragment_record(candidate_key(deep, wx, wy, k), f.p) : nullptr;
    if (r && cs.refine_band <= 1) {
        from = {Source::Own, 1, r, {}};
        return {r->E, r->ao, r->bent, r->dir};
    }
    const Interpolated in = interpolate_at(cache, f, record_site(scene, f, cs));
    if (!r) {
        from.src = in.weight > 0 ? Source::Records : Source::Missed;
        return {in.E, in.ao, in.bent, in.dir};
    }
    const float s = own_share(cs, f, in);
    from = {Source::Own, s, r, in.E};
    const Vec3 bent = r->bent * s + in.bent * (1 - s);
    Indirect out{r->E * s + in.E * (1 - s), r->ao * s + in.ao * (1 - s), dot(bent, bent) > 0 ? normalize(bent) : r->bent, {}};
    for (size_t c = 0; c < 3; ++c) out.light_dir[c] = r->dir[c] * s + in.dir[c] * (1 - s);
    return out;
}

/// The light at fragment k: through its front (front_indirect_at) and, on a thin translucent
/// surface, through its back, interpolated from the back side's records (refinement and
/// corrections are the front's alone).
Indirect indirect_at(const Scene& scene, const IrradianceCache& cache, const DeepBuffer& deep, int wx, int wy, uint32_t k, Origin& from) {
    Indirect out = front_indirect_at(scene, cache, deep, wx, wy, k, from);
    const Fragment& f = deep.pixel(wx, wy)[k];
    if (!takes_back_light(scene, f, cache.ao_only())) return out;
    const Interpolated back = interpolate_at(cache, f, record_site(scene, f, cache.settings(), Side::Back), Side::Back);
    out.back = back.E;
    from.back_missed = back.weight <= 0;
    return out;
}

/// Each light's share of what front_indirect_at gave fragment k (`from`), into `out`.
void front_shares_at(const Scene& scene, const IrradianceCache& cache, const DeepBuffer& deep, int wx, int wy, uint32_t k,
                     const Origin& from, std::span<Color> out) {
    const Fragment& f = deep.pixel(wx, wy)[k];
    if (from.src == Source::Missed || !needs_bounce_light(scene, f)) return;
    const Site site = record_site(scene, f, cache.settings());
    if (from.src == Source::Records) return light_shares_at(cache, f, site, out);
    for (size_t i = 0; i < out.size(); ++i) out[i] = from.record->parts->light[i].E * cache.light_scales()[i] * from.own;
    if (from.own < 1) {
        // Inside the refine band: each light's light of the blend, in proportion.
        std::vector<Color> interpolated(out.size());
        light_shares_at(cache, f, site, interpolated);
        const Color e = from.interpolated * (1 - from.own);
        for (size_t i = 0; i < out.size(); ++i) out[i] += interpolated[i] * e;
    }
    normalise_shares(out);
}

/// Each light's share of what indirect_at gave fragment k (`in`, `from`), into `out`: on a
/// thin translucent surface the two sides' shares weighed by what the indirect layer takes of
/// each, (1 - t) E_front and t E_back.
void shares_at(const Scene& scene, const IrradianceCache& cache, const DeepBuffer& deep, int wx, int wy, uint32_t k, const Indirect& in,
               const Origin& from, std::span<Color> out) {
    front_shares_at(scene, cache, deep, wx, wy, k, from, out);
    const Fragment& f = deep.pixel(wx, wy)[k];
    if (!takes_back_light(scene, f, cache.ao_only()) || from.back_missed) return;
    std::vector<Color> back(out.size(), Color(0));
    light_shares_at(cache, f, record_site(scene, f, cache.settings(), Side::Back), back, Side::Back);
    const float t = scene.materials[f.material].diffuse_transmission;
    const Color wf = from.src == Source::Missed ? Color(0) : in.irradiance * (1 - t), wb = in.back * t;
    for (size_t i = 0; i < out.size(); ++i) out[i] = out[i] * wf + back[i] * wb;
    normalise_shares(out);
}

/// A per-fragment record belongs to fragment `f` (its point, normal and key), made at `frame`.
void place_fragment_record(Record& r, const Fragment& f, uint64_t key, int frame) {
    r.p = r.origin = f.p, r.n = f.n;
    // Never used for reach; positive so the record is a valid one in a cache file.
    r.footprint = r.radius = r.raw_radius = f.footprint > 0 ? f.footprint : 1e-6f;
    r.key = key, r.frame = r.gathered = frame;
}

}  // namespace

namespace {
/// The guide of fragment f's refinement gather from the records about its record site.
std::optional<DirectionGuide> records_guide(const IrradianceCache& cache, const Scene& scene, const Fragment& f) {
    const Site site = record_site(scene, f, cache.settings());
    return guide_from_records(cache, site.p, site.n, f.n);
}

/// Whether fragment f's records disagree enough for a gather of its own (render.refine).
/// Hysteresis: refined in an earlier frame, a fragment keeps its own gather until its records
/// agree within refine_hold x refine, so that a spread hovering about the threshold does not
/// switch it on and off frame by frame. (Not within a frame: the lighting tool re-rendering it
/// shows what a render of that frame gives.)
bool wants_refinement(const Scene& scene, const IrradianceCache& cache, const Fragment& f, const Record* before,
                      const RefinementOptions& options) {
    const CacheSettings& cs = cache.settings();
    if (tilted_off_records(cs, f)) return true;
    const Interpolated in = interpolate_at(cache, f, record_site(scene, f, cs));
    const bool held =
        before ? before->gathered < options.frame : options.refined_before && options.refined_before->nearest(f.p, f.n, f.footprint);
    const float at = held ? cs.refine * cs.refine_hold : cs.refine;
    return !(in.weight > 0 && (cs.refine <= 0 || in.spread <= at));
}

/// Fragment k of pixel (wx, wy)'s own record, gathered about its own (displaced) point and
/// normal as brute force does; with an earlier gather near it on its surface, mostly from that
/// one's rays (then it keeps no hits: never reused itself, and `reused` is set).
Record gather_fragment_record(const Scene& scene, const DeepBuffer& deep, const Gatherer& refiner, const IrradianceCache& cache,
                              const RefinementOptions& options, int wx, int wy, uint32_t k, Counters& stats, bool& reused) {
    const Fragment& f = deep.pixel(wx, wy)[k];
    const FrameTiling& tiling = refiner.settings().tiling;
    const RandomStream rng = fragment_stream(tiling.seed, wx + deep.x0, wy + deep.y0, k);
    const Record* near = options.earlier ? options.earlier->nearest(f.p, f.n, f.footprint) : nullptr;
    auto hits = options.keep_hits && !near ? std::make_shared<GatherHits>() : nullptr;
    // Guided by the records that cover it where they kept a guide (render.guided), unless its
    // hits are to be kept (a guided gather has no grid to re-shade).
    const std::optional<DirectionGuide> guide =
        !near && !hits && refiner.settings().guided > 0 ? records_guide(cache, scene, f) : std::nullopt;
    const GatherResult g =
        near ? refiner.reproject(f.p, f.n, rng, {near->origin, near->n, record_stream(*near, tiling.seed, scene.camera.width), *near->hits},
                                 stats)
        : guide ? refiner.gather_guided(f.p, f.n, rng, *guide, stats)
                : refiner.gather(f.p, f.n, rng, stats, 0, hits.get());
    reused = near != nullptr;
    Record r;
    r.hits = std::move(hits);
    place_fragment_record(r, f, candidate_key(deep, wx, wy, k), options.frame);
    cache.set_values(r, g, false);  // a fragment's own value: no gradients
    r.harmonic = g.harmonic_distance, r.dmin = g.min_distance;
    r.rays = static_cast<uint32_t>(g.rays);
    return r;
}

/// Each process refined its own tiles: all take every process's records, and the count of
/// those made from earlier gathers.
void exchange_refined(Communicator& comm, std::vector<Record>& records, size_t& taken) {
    std::string mine = serialize_records(records);
    mine.append(reinterpret_cast<const char*>(&taken), sizeof(taken));
    const std::vector<std::string> all = comm.allgather(mine);
    records.clear(), taken = 0;
    for (const std::string& b : all) {
        size_t theirs = 0;
        std::memcpy(&theirs, b.data() + b.size() - sizeof(theirs), sizeof(theirs));
        taken += theirs;
        std::vector<Record> r = parse_records(b.substr(0, b.size() - sizeof(theirs)));
        records.insert(records.end(), std::make_move_iterator(r.begin()), std::make_move_iterator(r.end()));
    }
}
}  // namespace

size_t refinement_pass(const Scene& scene, const DeepBuffer& deep, const Gatherer& refiner, IrradianceCache& cache, Stats& stats,
                       ProgressSink* sink, const RefinementOptions& options) {
    const FrameTiling& tiling = refiner.settings().tiling;
    tbb::enumerable_thread_specific<std::vector<Record>> made;
    tbb::enumerable_thread_specific<size_t> reused(0);
    {
        // Lookups only: nobody inserts until every fragment is judged, so the decision sees the
        // finished cache whatever the thread count.
        auto lock = lock_cache<std::shared_lock<std::shared_mutex>>(cache, stats.local());
        for_each_pixel_in_tiles(
            deep, tiling.tile_size, sink, "refining",
            [&](int wx, int wy, size_t) {
                auto frags = deep.pixel(wx, wy);
                for (uint32_t k = 0; k < frags.size(); ++k) {
                    const Fragment& f = frags[k];
                    if (f.is_hair()) continue;  // hair keeps its strand's value (no fragment gathers)
                    if (!needs_bounce_light(scene, f)) continue;
                    const uint64_t key = candidate_key(deep, wx, wy, k);
                    if (cache.fragment_record(key, f.p)) continue;  // refined by an earlier render
                    // An earlier render's record of this very fragment, stale (what it saw changed).
                    const Record* before = nullptr;
                    if (options.stale)
                        if (auto it = options.stale->find(key); it != options.stale->end() && it->second.p == f.p) before = &it->second;
                    if (!wants_refinement(scene, cache, f, before, options)) continue;
                    if (before) {  // updated rather than gathered anew
                        made.local().push_back(options.update(*before, stats.local()));
                        continue;
                    }
                    bool from_earlier = false;
                    made.local().push_back(
                        gather_fragment_record(scene, deep, refiner, cache, options, wx, wy, k, stats.local(), from_earlier));
                    reused.local() += from_earlier;
                }
            },
            tiling.tile_order, options.comm);
    }
    std::vector<Record> records;
    for (auto& v : made) records.insert(records.end(), v.begin(), v.end());
    size_t taken = 0;
    for (size_t n : reused) taken += n;
    if (options.comm && options.comm->size() > 1) exchange_refined(*options.comm, records, taken);
    std::sort(records.begin(), records.end(), [](const Record& a, const Record& b) { return a.key < b.key; });
    auto lock = lock_cache<std::unique_lock<std::shared_mutex>>(cache, stats.local());
    for (const Record& r : records) cache.replace_fragment_record(r);
    stats.set("refined_fragments", static_cast<double>(records.size() - taken));
    stats.set("refined_from_earlier_gathers", static_cast<double>(taken));
    stats.set("refine_rays_per_gather", static_cast<double>(refiner.grid().rays()));
    return records.size() - taken;
}

InterpolatedLight interpolation_pass(const Scene& scene, const DeepBuffer& deep, const IrradianceCache& cache, const FrameTiling& tiling,
                                     Stats& stats, ProgressSink* sink, bool report, bool per_light) {
    InterpolatedLight out;
    out.light.resize(deep.fragments.size());
    out.refined.assign(deep.fragments.size(), 0);
    if (per_light) {
        if (!cache.has_light_parts(scene.lights.size())) throw std::logic_error("interpolation: records have no light parts");
        out.shares.lights = scene.lights.size();
        out.shares.share.assign(deep.fragments.size() * scene.lights.size(), Color(0));
    }
    tbb::enumerable_thread_specific<uint64_t> misses(0), lookups(0), own(0);
    // The pass holds the shared lock for its workers: no writer can interleave.
    auto lock = lock_cache<std::shared_lock<std::shared_mutex>>(cache, stats.local());
    for_each_pixel_in_tiles(
        deep, tiling.tile_size, sink, "interpolate",
        [&](int wx, int wy, size_t first) {
            auto frags = deep.pixel(wx, wy);
            for (uint32_t k = 0; k < frags.size(); ++k) {
                Origin from;
                out.light[first + k] = indirect_at(scene, cache, deep, wx, wy, k, from);
                if (per_light) shares_at(scene, cache, deep, wx, wy, k, out.light[first + k], from, out.shares.at(first + k));
                ++lookups.local();
                if (from.src == Source::Own) {
                    ++own.local();
                    out.refined[first + k] = 1;
                }
                misses.local() += from.src == Source::Missed || from.back_missed;
            }
        },
        tiling.tile_order);
    uint64_t m = 0, l = 0, o = 0;
    for (auto v : misses) m += v;
    for (auto v : lookups) l += v;
    for (auto v : own) o += v;
    if (report) {
        stats.set("shading_misses", static_cast<double>(m));
        stats.set("lookups", static_cast<double>(l));
        stats.set("fragment_records_used", static_cast<double>(o));
    }
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
            Origin unused;
            for (uint32_t k = 0; k < frags.size(); ++k)
                out[first + k] = indirect_at(scene, cache, deep, lx, ly, std::min(k, n - 1), unused);
        }
    });
    return out;
}

}  // namespace bounce
