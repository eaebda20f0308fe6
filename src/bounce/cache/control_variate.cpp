#include "bounce/cache/control_variate.h"

#include <tbb/enumerable_thread_specific.h>

#include <cmath>
#include <optional>

#include "bounce/cache/sites.h"
#include "bounce/core/random.h"

namespace bounce {

namespace {

/// The centre direction of each bin, in the bins' frame (z up).
const std::array<Vec3, kReachBins>& bin_centres() {
    static const std::array<Vec3, kReachBins> centres = [] {
        std::array<Vec3, kReachBins> c{};
        for (int band = 0; band < kReachBands; ++band)
            for (int sector = 0; sector < kReachSectors; ++sector) {
                const float sin2 = (static_cast<float>(band) + 0.5f) / kReachBands;
                const float phi = 2 * kPi * (static_cast<float>(sector) + 0.5f) / kReachSectors;
                const float s = std::sqrt(sin2);
                c[static_cast<size_t>(band * kReachSectors + sector)] = {s * std::cos(phi), s * std::sin(phi), std::sqrt(1 - sin2)};
            }
        return c;
    }();
    return centres;
}

/// The covering records' per-bin values (`values(record)`: its 32, or null to skip it) looked
/// up at the centres of the bins of Frame(gather_n) and blended with their weights (a record
/// whose hemisphere does not hold a direction leaves it to the others). Returns how many
/// records took part.
template <class T, class Values>
int blend_bins(const IrradianceCache& cache, const Vec3& p, const Vec3& n, const Vec3& gather_n, const Values& values,
               std::array<T, kReachBins>& out) {
    std::array<float, kReachBins> weight{};
    const Frame frame(gather_n);
    const auto& centres = bin_centres();
    int records = 0;
    cache.visit_weights(p, n, [&](uint32_t id, float w) {
        if (!(w > 0)) return;
        const Record& r = cache.record(id);
        const std::array<T, kReachBins>* v = values(r);
        if (!v) return;
        ++records;
        if (r.n == gather_n) {  // the same frame: bin for bin (planar surfaces, the common case)
            for (size_t b = 0; b < out.size(); ++b) out[b] += (*v)[b] * w, weight[b] += w;
            return;
        }
        const Frame rf(r.n);
        for (size_t b = 0; b < out.size(); ++b) {
            const Vec3 local = rf.to_local(frame.to_world(centres[b]));
            if (local.z <= 0) continue;  // below the record's horizon: it saw nothing there
            out[b] += (*v)[static_cast<size_t>(direction_bin(local))] * w, weight[b] += w;
        }
    });
    for (size_t b = 0; b < out.size(); ++b) out[b] = weight[b] > 0 ? out[b] / weight[b] : T(0);
    return records;
}

}  // namespace

BinPrediction predict_bins(const IrradianceCache& cache, const Vec3& p, const Vec3& n, const Vec3& gather_n) {
    BinPrediction out;
    out.records = blend_bins(
        cache, p, n, gather_n, [](const Record& r) { return &r.bin_values(); }, out.bin);
    return out;
}

std::optional<DirectionGuide> guide_from_records(const IrradianceCache& cache, const Vec3& p, const Vec3& n, const Vec3& gather_n) {
    DirectionGuide out;
    out.n = gather_n;
    const auto spread = [](const Record& r) { return r.guide ? &r.guide->spread : nullptr; };
    if (blend_bins(cache, p, n, gather_n, spread, out.spread) == 0) return std::nullopt;
    return out;
}

Color prediction_correction(const BinPrediction& prediction, std::span<const Vec3> local, float scale) {
    if (prediction.records == 0 || local.empty()) return Color(0);
    Color integral(0), along(0);
    for (const Color& c : prediction.bin) integral += c;
    for (const Vec3& d : local) along += prediction.bin[static_cast<size_t>(direction_bin(d))];
    return (integral / static_cast<float>(kReachBins) - along / static_cast<float>(local.size())) * scale;
}

Color plane_correction(const IrradianceCache& cache, const Vec3& p, const Vec3& n, std::span<const Vec3> local, float scale, int& records) {
    Color integral(0), along(0);
    float wsum = 0;
    records = 0;
    cache.visit_weights(p, n, [&](uint32_t id, float w) {
        const Record& r = cache.record(id);
        if (!(w > 0) || !r.cells || !(r.n == n)) return;
        ++records;
        Color sum(0);
        for (const Color& c : *r.cells) sum += c;
        integral += sum * (w / static_cast<float>(r.cells->size()));
        for (const Vec3& d : local) along += (*r.cells)[static_cast<size_t>(grid_cell(r.grid, d))] * (w / static_cast<float>(local.size()));
        wsum += w;
    });
    if (records == 0) return Color(0);
    return (integral - along) * (scale / wsum);
}

Color hits_correction(const IrradianceCache& cache, const Vec3& p, const Vec3& n, const Vec3& at, const Vec3& gather_n,
                      std::span<const Vec3> local, float scale, int& records) {
    static const GatherGrid fine{kHitRows, kHitCols};
    const Frame frame(gather_n);
    std::vector<Color> value(static_cast<size_t>(fine.rays()), Color(0));
    std::vector<float> weight(value.size(), 0.0f);
    records = 0;
    cache.visit_weights(p, n, [&](uint32_t id, float w) {
        const Record& r = cache.record(id);
        if (!(w > 0) || !r.cell_hits || !r.cells) return;
        ++records;
        const std::vector<Vec3>& hits = *r.cell_hits;
        for (size_t c = 0; c < hits.size(); ++c) {
            const Vec3 d = frame.to_local(hits[c] - at);
            if (!(d.z > 0)) continue;  // behind the fragment's plane: none of its rays go there
            const auto cell = static_cast<size_t>(grid_cell(fine, d / length(d)));
            value[cell] += (*r.cells)[c] * w, weight[cell] += w;
        }
    });
    if (records == 0) return Color(0);
    // A cell no hit reached takes the records' bins (each fine cell lies inside one bin), blended
    // only if some cell needs them: a second visit of the records.
    std::optional<BinPrediction> bins;
    Color integral(0), along(0);
    for (int j = 0; j < fine.m; ++j)
        for (int k = 0; k < fine.n; ++k) {
            const auto cell = static_cast<size_t>(j * fine.n + k);
            if (weight[cell] > 0) {
                value[cell] = value[cell] / weight[cell];
            } else {
                if (!bins) bins = predict_bins(cache, p, n, gather_n);
                value[cell] = bins->bin[static_cast<size_t>(direction_bin(gather_cell_direction(fine, j, k, 0.5f, 0.5f)))];
            }
            integral += value[cell];
        }
    for (const Vec3& d : local) along += value[static_cast<size_t>(grid_cell(fine, d))];
    return (integral / static_cast<float>(value.size()) - along / static_cast<float>(local.size())) * scale;
}

void correction_pass(const Scene& scene, const DeepBuffer& deep, const IrradianceCache& cache, const Gatherer& gatherer,
                     std::vector<Indirect>& light, Stats& stats, ProgressSink* progress) {
    const bool ao = gatherer.settings().ao;
    const bool hits = gatherer.settings().prediction_hits;
    tbb::enumerable_thread_specific<std::vector<Vec3>> directions;
    tbb::enumerable_thread_specific<uint64_t> fragments(0), predicted(0);
    for_each_bounce_fragment(scene, deep, gatherer.settings().tiling, progress, "correct", [&](const BounceFragment& b) {
        Counters& counters = stats.local();
        std::vector<Vec3>& local = directions.local();
        // The gather brute force makes here (the same point, normal and stream) ...
        const HairSite& at = b.site;
        const GatherResult g = gatherer.gather(at.p, at.n, b.rng, counters);
        // ... corrected by the records' prediction about the site they are looked up at.
        const Site site = record_site(scene, b.f, cache.settings());
        gather_local_directions(gatherer.grid(), b.rng, local);
        int records = 0;  // the records' hits, or those on its own plane; else the records' bins
        const float scale = ao ? 1.0f : kPi;
        Color c = hits ? hits_correction(cache, site.p, site.n, at.p, at.n, local, scale, records)
                       : plane_correction(cache, site.p, at.n, local, scale, records);
        if (records == 0) {
            const BinPrediction pred = predict_bins(cache, site.p, site.n, at.n);
            c = prediction_correction(pred, local, scale), records = pred.records;
        }
        Indirect& out = light[b.index];
        if (ao)
            out.ao = g.ao + c.x;
        else
            out.irradiance = g.irradiance + c;
        ++fragments.local();
        predicted.local() += records > 0;
    });
    uint64_t n = 0, p = 0;
    for (uint64_t v : fragments) n += v;
    for (uint64_t v : predicted) p += v;
    stats.set("correction_fragments", static_cast<double>(n));
    stats.set("correction_predicted", static_cast<double>(p));
}

}  // namespace bounce
