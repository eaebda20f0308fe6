// Record values filtered in record space (issue 47, route 2; docs/irradiance-cache.md,
// "Filtering records"). A record's gather is a Monte Carlo estimate; its error is spread over
// its whole footprint, so neighbouring records' independent errors show as low-frequency
// blotches in a still and as flicker in a shot. Before the shading pass interpolates, each
// record's irradiance and AO are replaced by a cross-bilateral mean over its neighbours: each
// neighbour's value extrapolated to the record with its gradients, weighed by its
// interpolation weight there (the metric's position, normal, gradient and behind tests: no
// record that could not serve the point) and by a range kernel on the difference of the two
// values in units of their estimated noise, so a difference noise explains is averaged and a
// real edge is kept.
#pragma once

#include <vector>

#include "bounce/cache/irradiance_cache.h"

namespace bounce {

/// Every record's filtered value (index = record id), with the range kernel `width` (in noise
/// widths; CacheSettings::record_filter, > 0). A record whose neighbours are all rejected keeps
/// its own value; so does every record of a cache with the Ward metric, whose weight at a
/// record's own point is unbounded.
std::vector<FilteredValue> filter_record_values(const IrradianceCache& cache, float width);

}  // namespace bounce
