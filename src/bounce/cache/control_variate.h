// Records as a control variate for a per-fragment gather (issue 47; docs/gather.md, "Records as
// a control variate"). The records that cover a fragment predict, per direction, the radiance
// its rays will meet (their direction bins, GatherResult::bins, blended with their
// interpolation weights); the prediction is piecewise constant over the fragment's own 32 bins,
// each 1/32 of the cosine-weighted hemisphere, so its integral is known exactly. A fragment's
// estimate is its own N-ray gather plus that integral minus the prediction's N-ray estimate
// along the same rays: unbiased for any prediction, brute force itself when the prediction is
// 0, and without variance where the prediction is the truth.
#pragma once

#include <array>
#include <optional>
#include <span>
#include <vector>

#include "bounce/cache/irradiance_cache.h"
#include "bounce/core/stats.h"
#include "bounce/deep/deep_buffer.h"
#include "bounce/gather/gather.h"
#include "bounce/gather/guide.h"

namespace bounce {

/// The prediction at one fragment: a value per bin of its gather's frame.
struct BinPrediction {
    std::array<Color, kReachBins> bin{};
    int records = 0;  ///< records that made it (0: the prediction is 0)
};

/// The records of `cache` covering (p, n) (weighed as interpolation weighs them), each centre
/// of the bins of Frame(gather_n) looked up in every record's bins and blended with the
/// records' weights (a record whose hemisphere does not hold the direction leaves it to the
/// others). gather_n: the normal the fragment's rays are gathered about (a displaced
/// fragment's own, where its records lie on the un-displaced surface).
BinPrediction predict_bins(const IrradianceCache& cache, const Vec3& p, const Vec3& n, const Vec3& gather_n);

/// The guide of a refinement gather at (p, n) about gather_n (render.guided, gather/guide.h):
/// the covering records' spreads (Record::guide) blended as predict_bins blends their bins;
/// none when no covering record kept one.
std::optional<DirectionGuide> guide_from_records(const IrradianceCache& cache, const Vec3& p, const Vec3& n, const Vec3& gather_n);

/// What the control variate adds to a gather's value: `scale` x (the mean of the prediction
/// over the bins minus its mean over the gather's rays), `local`: the rays' directions in the
/// gather's frame. `scale` is pi for irradiance (E = pi/S sum L), 1 for AO (a mean).
Color prediction_correction(const BinPrediction& prediction, std::span<const Vec3> local, float scale);

/// The same from the records on the fragment's own plane (normal `n` to the bit) that keep
/// their every cell: a ray's prediction is the radiance of the cell of each record's grid it
/// falls in, blended; the integral is each record's own mean. `records`: how many.
Color plane_correction(const IrradianceCache& cache, const Vec3& p, const Vec3& n, std::span<const Vec3> local, float scale, int& records);

/// The same from the records' cells' hit points (Record::cell_hits) seen from the fragment's
/// gather point `at` (normal gather_n), records looked up at (p, n): each hit, weighed by its
/// record's interpolation weight, goes to the cell of a fine grid over the fragment's hemisphere
/// (kHitRows x kHitCols cells of equal cosine-weighted measure) it is seen in; a cell no hit
/// reaches takes the records' bins there. The prediction is piecewise constant over those
/// cells, so its integral is their mean. `records`: how many took part.
inline constexpr int kHitRows = 16, kHitCols = 64;
Color hits_correction(const IrradianceCache& cache, const Vec3& p, const Vec3& n, const Vec3& at, const Vec3& gather_n,
                      std::span<const Vec3> local, float scale, int& records);

/// The correction pass: every fragment that uses the bounce light gathers `gatherer`'s rays
/// (CacheSettings::correction_rays) at its own point and seed, as brute force does, and its
/// irradiance (AO in AO mode) becomes that gather corrected by the records' prediction; its bent
/// normal and light directions stay the interpolation's. `light`: the interpolation pass's
/// result, parallel to deep.fragments. Sets the stats correction_fragments, correction_predicted.
void correction_pass(const Scene& scene, const DeepBuffer& deep, const IrradianceCache& cache, const Gatherer& gatherer,
                     std::vector<Indirect>& light, Stats& stats, ProgressSink* progress);

}  // namespace bounce
