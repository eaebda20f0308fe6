// The two passes of a final-quality cache render (TL04): a gathering pass that walks the image
// in hierarchical-refinement sub-passes and creates records where lookups miss, then a shading
// pass that only interpolates. Also the single progressive preview pass.
#pragma once

#include <functional>
#include <unordered_map>
#include <vector>

#include "bounce/cache/irradiance_cache.h"
#include "bounce/core/communicator.h"
#include "bounce/core/progress.h"
#include "bounce/core/stats.h"
#include "bounce/deep/deep_buffer.h"
#include "bounce/gather/gather.h"

namespace bounce {

/// One sub-pass of the gathering pass: pixels on a lattice of spacing `step` (full-image
/// coordinates), in one of three parity classes (or all of them for the first level), and in
/// one of four quarter classes of that, so candidates within a sub-pass are 4 steps apart
/// (2 for the first level's) and a record made in it rarely covers another candidate of it.
struct SubPass {
    int step = 1;
    int parity = 0;    ///< bit 0: x/step odd, bit 1: y/step odd
    bool all = false;  ///< first level: every parity
    int quarter = 0;   ///< bit 0: x/(2 step) odd, bit 1: y/(2 step) odd (x/step, y/step at the first level)
    bool contains(int x, int y) const;
    /// Its pixels form a lattice: x = offset(0) and y = offset(1), modulo period().
    int period() const { return all ? 2 * step : 4 * step; }
    int offset(int axis) const {
        const int q = (quarter >> axis) & 1;
        return all ? q * step : step * (((parity >> axis) & 1) + 2 * q);
    }
    /// The first coordinate of the lattice along `axis` (0: x, 1: y) at or after `from`.
    int first(int from, int axis) const { return from + ((offset(axis) - from) % period() + period()) % period(); }
};

/// The sub-passes of a gathering pass: every `first_step` pixels, then the pixels between,
/// halving the step down to 1.
std::vector<SubPass> subpass_schedule(int first_step);

/// Called after each sub-pass with the fraction done (preview mode shows the image then).
using SubPassCallback = std::function<void(const SubPass&, size_t index, size_t count)>;

class StaleRecords;
class EarlierGathers;

/// What a gathering pass does besides making records where lookups miss.
struct GatheringOptions {
    SubPassCallback after_subpass;  ///< called after each sub-pass (preview)
    int frame = 0;                  ///< stamped on new records
    /// CacheSettings::min_rays: a record gathers with it first and with the full gatherer only
    /// when that estimate's relative standard error exceeds CacheSettings::ray_noise.
    const Gatherer* first = nullptr;
    /// Records of earlier frames that need a new gather (temporal.h): every one that covers a
    /// fragment's point is redone (in place, its own random stream), and a miss they cover waits
    /// for them instead of making a new record.
    StaleRecords* stale = nullptr;
    bool keep_hits = false;  ///< new records keep their gather's hits (re-shading in later frames)
    /// A record whose weight at a point reaches this covers it alone (IrradianceCache::misses).
    /// Frames of a shot lower it: fragments move a little each frame, and a point next to a kept
    /// record is as well served as the record's own.
    float own_weight = 0.99f;
    float min_weight = -1;  ///< > 0: the weight sum a point needs (IrradianceCache::misses), else the settings'
    /// PerThread: each tile judges against the cache as the sub-pass began plus its own new
    /// records only (ParallelSettings::cache_sharing).
    CacheSharing sharing = CacheSharing::Shared;
    /// The processes of an MPI job (core/communicator.h): each judges its own tiles of a
    /// sub-pass and the tiles' work is exchanged before it is merged (null: this process alone).
    Communicator* comm = nullptr;
};

/// Gathering pass: creates records until every fragment of `deep` has a covered lookup.
/// Within a sub-pass every lookup sees the cache as it was when the sub-pass began; new
/// records are inserted in pixel order (redone stale records first, in their order), dropping
/// those the earlier ones already cover, so the cache does not depend on thread count or
/// scheduling. Records on an object that moves in the shot carry their anchor on it. The
/// gatherer's tiling (GatherSettings::tiling) lays out the tiles and streams.
void gathering_pass(const Scene& scene, const DeepBuffer& deep, const Gatherer& gatherer, IrradianceCache& cache, Stats& stats,
                    ProgressSink* progress, const GatheringOptions& options = {});

/// Per-fragment refinement (when the plan lists a RefineStep), after the gathering pass: a fragment
/// whose covering records disagree (the spread of their extrapolated values at the fragment
/// exceeds `refine`), that no record covers, or whose displaced normal tilts from the
/// un-displaced one by more than `refine_tilt` (records on the un-displaced surface) gets a
/// gather of its own about its own point and normal with `refiner`, stored
/// as a fragment record (IrradianceCache::insert_fragment_record) that no other fragment
/// uses. Fragments that already have one (a loaded cache) are skipped. Every fragment is
/// judged against the finished cache and the records are inserted in key order afterwards:
/// deterministic at any thread count. Returns how many were made. The refiner's tiling
/// (GatherSettings::tiling) lays out its tiles and streams.

/// What a refinement pass does besides gathering fragments' own records.
struct RefinementOptions {
    int frame = 0;           ///< stamped on new records
    bool keep_hits = false;  ///< new records keep their gather's hits
    /// Frames of a shot: earlier frames' fragment records to update (by key; used when the
    /// fragment is at exactly the same point) rather than gather anew, and how.
    const std::unordered_map<uint64_t, Record>* stale = nullptr;
    std::function<Record(const Record&, Counters&)> update;
    /// ... and earlier gathers near a fragment, whose rays it reuses (temporal.h).
    const EarlierGathers* earlier = nullptr;
    /// ... and where refinement gathered in the frame before, for a moving camera: a fragment
    /// near one on its surface keeps CacheSettings::refine_hold.
    const EarlierGathers* refined_before = nullptr;
    Communicator* comm = nullptr;  ///< as GatheringOptions::comm: each process refines its own tiles
};

size_t refinement_pass(const Scene& scene, const DeepBuffer& deep, const Gatherer& refiner, IrradianceCache& cache, Stats& stats,
                       ProgressSink* progress, const RefinementOptions& options = {});

/// What the shading pass's interpolation gives every fragment.
struct InterpolatedLight {
    std::vector<Indirect> light;   ///< parallel to deep.fragments
    std::vector<uint8_t> refined;  ///< 1 where a fragment took its own (refinement) record
    size_t misses = 0;             ///< fragments no record covered (left black)
    LightShares shares;            ///< with `per_light` only
};

/// Interpolation of the shading pass: never creates a record. A fragment takes its fragment
/// record if it has one, else the interpolation. Misses (no record applies; the gathering pass
/// makes them impossible) are counted (and in stats as "shading_misses") and left black, so a
/// bug shows.
/// `report`: sets the stats (shading_misses, lookups, fragment_records_used).
/// `per_light` (the records must keep light parts): also each light's share of every fragment's light.
InterpolatedLight interpolation_pass(const Scene& scene, const DeepBuffer& deep, const IrradianceCache& cache, const FrameTiling& tiling,
                                     Stats& stats, ProgressSink* progress, bool report = true, bool per_light = false);

/// Progressive preview after a sub-pass of step `step`: each fragment takes the interpolated
/// light at the nearest pixel (on that step's lattice, then coarser ones) a finished sub-pass
/// visited (`visited`, one flag per window pixel); a fragment record counts for its own pixel.
std::vector<Indirect> preview_indirect(const Scene& scene, const DeepBuffer& deep, const IrradianceCache& cache,
                                       const std::vector<uint8_t>& visited, int step);

}  // namespace bounce
