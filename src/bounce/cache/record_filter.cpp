#include "bounce/cache/record_filter.h"

#include <algorithm>
#include <cmath>

#include "bounce/core/parallel.h"

namespace bounce {

namespace {

/// Record `id`'s value filtered with its neighbours' (record_filter.h).
FilteredValue filtered_record(const IrradianceCache& cache, uint32_t id, float width) {
    const Record& ri = cache.record(id);
    const bool ao = cache.ao_only();
    const float floor = ao ? 1e-3f : std::max(cache.luminance_floor(), 1e-12f);
    const float own = std::max(ao ? ri.ao : luminance(ri.E), floor);
    Color esum(0);
    double asum = 0, wsum = 0;
    cache.visit_weights(
        ri.p, ri.n,
        [&](uint32_t j, float w) {
            if (!(w > 0)) return;
            const Record& rj = cache.record(j);
            const Vec3 dp = ri.p - rj.p, rot = cross(rj.n, ri.n);
            const Color e = j == id ? rj.E : extrapolated(rj.E, rj.grad_t, rj.grad_r, dp, rot);
            const float a = j == id ? rj.ao : extrapolated_ao(rj.ao, rj.ao_grad_t, rj.ao_grad_r, dp, rot);
            float k = w;
            if (j != id) {
                // The range kernel: the difference in units of what the two records' noise
                // would make it (their relative standard errors, independent).
                const float sigma = width * std::sqrt(ri.noise * ri.noise + rj.noise * rj.noise);
                const float d = std::abs((ao ? a : luminance(e)) - own) / own;
                k *= sigma > 0 ? std::exp(-0.5f * (d / sigma) * (d / sigma)) : 0.0f;
            }
            if (!(k > 0)) return;
            // Differences from its own value: a constant field stays bit-exact.
            esum += (e - ri.E) * k, asum += static_cast<double>(a - ri.ao) * k, wsum += k;
        },
        true);
    if (!(wsum > 0)) return {ri.E, ri.ao};
    const auto inv = static_cast<float>(1 / wsum);
    return {ri.E + esum * inv, ri.ao + static_cast<float>(asum / wsum)};
}

}  // namespace

std::vector<FilteredValue> filter_record_values(const IrradianceCache& cache, float width) {
    std::vector<FilteredValue> out(cache.size());
    if (cache.settings().metric == Metric::Ward) {
        for (size_t i = 0; i < out.size(); ++i) out[i] = {cache.record(i).E, cache.record(i).ao};
        return out;
    }
    // Each value reads only the records as they are, so the order (and thread count) does
    // not matter: the result is deterministic.
    parallel_for_each_index(size_t(0), out.size(), [&](size_t i) { out[i] = filtered_record(cache, static_cast<uint32_t>(i), width); });
    return out;
}

}  // namespace bounce
