// The work a shot's next frame does on what the frame before left (docs/animation.md), after
// temporal.h has judged it: stale records redone (re-shaded from their hits, updated where
// movers cross their rays, or gathered again), earlier fragment records updated, the
// refinement gathers the next frame keeps, and where refinement gathered the frame before.
#pragma once

#include <functional>
#include <memory>
#include <vector>

#include "bounce/cache/irradiance_cache.h"
#include "bounce/cache/temporal.h"
#include "bounce/gather/gather.h"
#include "bounce/scene/changes.h"
#include "bounce/scene/scene.h"

namespace bounce {

/// What redoing earlier records needs to know of the frame: its scene, what changed since the
/// frame before (null for none), its number, whether records keep their hits, its seed (records'
/// streams) and its cache settings (the temporal filter).
struct TemporalFrame {
    const Scene& scene;
    const SceneChanges* changes;
    int frame;
    bool keep_hits;
    uint64_t seed;
    const CacheSettings& settings;
};

/// Temporal filtering (render.temporal_filter): a redone record keeps share `f` of its previous values.
void blend_with_previous(Record& r, const Record& old, float f);
/// How a stale record of an earlier frame is redone (StaleRecords' Redo).
StaleRecords::Redo redo_function(const TemporalFrame& now, const IrradianceCache& cache, const Gatherer& gatherer);
/// How an earlier frame's fragment record is updated (refinement's RefinementOptions::update).
std::function<Record(const Record&, Counters&)> fragment_update_function(const TemporalFrame& now, const Gatherer& refiner,
                                                                         const IrradianceCache& cache);
/// The refinement gathers whose rays the next frame may reuse, by frame and key.
std::vector<Record> gathers_to_keep(const EarlierGathers& earlier, const IrradianceCache& cache, int frame);
/// Where refinement gathered in the frame before, for a moving camera's hold; null when there is none.
std::unique_ptr<EarlierGathers> refined_the_frame_before(const IrradianceCache& cache, const TemporalJudgement& judged, const Scene& scene,
                                                         const CacheSettings& settings, int frame);

}  // namespace bounce
