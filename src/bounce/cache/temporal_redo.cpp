#include "bounce/cache/temporal_redo.h"

#include <algorithm>

namespace bounce {

/// Temporal filtering (render.temporal_filter): a redone record keeps share `f` of its previous
/// values (irradiance, AO, light directions and gradients; its reach is the new gather's).
void blend_with_previous(Record& r, const Record& old, float f) {
    if (f <= 0) return;
    r.parts.reset();  // a blend is no longer its light parts' sum
    const auto mix = [f](auto now, auto was) { return now * (1 - f) + was * f; };
    r.E = mix(r.E, old.E), r.ao = mix(r.ao, old.ao);
    for (size_t c = 0; c < 3; ++c)
        r.dir[c] = mix(r.dir[c], old.dir[c]), r.grad_r[c] = mix(r.grad_r[c], old.grad_r[c]), r.grad_t[c] = mix(r.grad_t[c], old.grad_t[c]);
    r.ao_grad_r = mix(r.ao_grad_r, old.ao_grad_r), r.ao_grad_t = mix(r.ao_grad_t, old.ao_grad_t);
    const Vec3 bent = mix(r.bent, old.bent);
    if (dot(bent, bent) > 0) r.bent = normalize(bent);
}

/// How a stale record of an earlier frame is redone: re-shaded from its hits when only its
/// light changed and it kept them, else gathered again in place with its own random stream;
/// its reach and gradients as a new record's, its anchor and creation frame kept.
StaleRecords::Redo redo_function(const TemporalFrame& now, const IrradianceCache& cache, const Gatherer& gatherer) {
    const uint64_t seed = now.seed;
    const int width = now.scene.camera.width;
    std::vector<Bounds> boxes = now.changes ? moving_bounds(*now.changes) : std::vector<Bounds>();
    return [&cache, &gatherer, seed, width, frame = now.frame, keep = now.keep_hits, boxes = std::move(boxes)](
               const Record& old, StaleReason why, Counters& counters) {
        const RandomStream rng = record_stream(old, seed, width);
        std::shared_ptr<GatherHits> hits;
        GatherResult g;
        if (why == StaleReason::Update && old.hits && old.hits->m == gatherer.grid().m && old.hits->n == gatherer.grid().n) {
            // Only the rays through moving objects' swept bounds are traced again.
            auto updated = std::make_shared<GatherHits>(*old.hits);
            std::vector<uint32_t> cells;
            cells_through(gatherer.grid(), old.origin, old.n, rng, *updated, boxes, cells);
            g = gatherer.update(old.origin, old.n, rng, *updated, cells, counters, old.near);
            hits = std::move(updated);
        } else if (why == StaleReason::Light && old.hits) {
            g = gatherer.reshade(old.origin, old.n, rng, *old.hits, counters, old.near);
            hits = std::const_pointer_cast<GatherHits>(old.hits);
        } else {
            if (keep) hits = std::make_shared<GatherHits>();
            g = gatherer.gather(old.origin, old.n, rng, counters, old.near, hits.get());
        }
        Record r = cache.make_record(g, old.p, old.n, old.footprint, old.key);
        // Its nearest hits where they were: it keeps its reach, neighbour clamps included (clamped
        // again as it is inserted among other records, it would depend on their order).
        if (cache.settings().metric != Metric::Hessian && g.min_distance == old.dmin && g.harmonic_distance == old.harmonic)
            cache.set_raw_radius(r, old.raw_radius, old.radius);
        blend_with_previous(r, old, cache.settings().temporal_filter);
        r.origin = old.origin, r.near = old.near, r.frame = old.frame, r.gathered = frame;
        r.anchor = old.anchor, r.anchor_p = old.anchor_p, r.anchor_n = old.anchor_n, r.anchor_prim = old.anchor_prim;
        r.hits = std::move(hits);
        return r;
    };
}

/// How an earlier frame's fragment record is updated: the rays through moving objects' swept
/// bounds traced again, every hit re-shaded (a fresh gather with its stream, for less).
std::function<Record(const Record&, Counters&)> fragment_update_function(const TemporalFrame& now, const Gatherer& refiner,
                                                                         const IrradianceCache& cache) {
    std::vector<Bounds> boxes = now.changes ? moving_bounds(*now.changes) : std::vector<Bounds>();
    return [&refiner, &cache, seed = now.seed, width = now.scene.camera.width, frame = now.frame, boxes = std::move(boxes),
            filter = now.settings.temporal_filter](const Record& old, Counters& counters) {
        const RandomStream rng = record_stream(old, seed, width);
        auto hits = std::make_shared<GatherHits>(*old.hits);
        std::vector<uint32_t> cells;
        cells_through(refiner.grid(), old.origin, old.n, rng, *hits, boxes, cells);
        const GatherResult g = refiner.update(old.origin, old.n, rng, *hits, cells, counters);
        Record r = old;
        cache.set_values(r, g, false);
        blend_with_previous(r, old, filter);
        r.harmonic = g.harmonic_distance, r.dmin = g.min_distance, r.gathered = frame, r.drift = 0;
        r.hits = std::move(hits);
        return r;
    };
}

/// The refinement gathers whose rays the next frame may reuse: earlier ones that still serve and
/// this frame's (traced, not reprojected: those keep hits), by frame and key.
std::vector<Record> gathers_to_keep(const EarlierGathers& earlier, const IrradianceCache& cache, int frame) {
    std::vector<Record> out = earlier.lasting(frame);
    for (size_t i = 0; i < cache.fragment_record_count(); ++i)
        if (const Record& r = cache.fragment_record_at(i); r.gathered == frame && r.hits) out.push_back(r);
    std::sort(out.begin(), out.end(),
              [](const Record& a, const Record& b) { return a.gathered != b.gathered ? a.gathered < b.gathered : a.key < b.key; });
    return out;
}

/// Where refinement gathered in the frame before, for a moving camera's hold (its fragments
/// never land on those points): this frame's fragment near one keeps CacheSettings::refine_hold.
/// Null when there is no hold.
std::unique_ptr<EarlierGathers> refined_the_frame_before(const IrradianceCache& cache, const TemporalJudgement& judged, const Scene& scene,
                                                         const CacheSettings& cs, int frame) {
    if (cs.refine_hold_reach <= 0 || cs.refine_hold >= 1) return nullptr;
    std::vector<Record> last;
    for (size_t i = 0; i < cache.fragment_record_count(); ++i)
        if (const Record& r = cache.fragment_record_at(i); r.gathered == frame - 1) last.push_back(r);
    for (const auto& [key, r] : judged.fragment_stale)
        if (r.gathered == frame - 1) last.push_back(r);
    // By key: the index's order (and so the nearest's ties) is the same whatever the hash map's.
    std::sort(last.begin(), last.end(), [](const Record& a, const Record& b) { return a.key < b.key; });
    return std::make_unique<EarlierGathers>(std::move(last), scene.bounds(), cs.refine_hold_reach, false);
}

}  // namespace bounce
