#include "bounce/cache/irradiance_cache.h"

#include "bounce/cache/record_filter.h"
#include "bounce/core/parallel.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace bounce {

namespace {

/// How much of a record's translational gradient holds out to the minimum spacing `rmin` when
/// its raw radius is `raw` (ic-algorithms.md 2.4): raw / rmin below it, else all.
float raised_share(float raw, float rmin) { return raw < rmin && rmin > 0 ? std::max(raw, 0.0f) / rmin : 1.0f; }

}  // namespace

IrradianceCache::IrradianceCache(const Bounds& scene_bounds, CacheSettings settings, bool ao_only)
    : scene_bounds_(scene_bounds),
      settings_(std::move(settings)),
      shading_settings_(settings_.for_shading()),
      metric_(settings_),
      shading_metric_(shading_settings_),
      ao_only_(ao_only),
      octree_(scene_bounds) {}

IrradianceCache::IrradianceCache(const IrradianceCache& o)
    : scene_bounds_(o.scene_bounds_),
      settings_(o.settings_),
      shading_settings_(o.shading_settings_),
      metric_(o.metric_),
      shading_metric_(o.shading_metric_),
      ao_only_(o.ao_only_),
      records_(o.records_),
      shapes_(o.shapes_),
      fragment_records_(o.fragment_records_),
      fragment_index_(o.fragment_index_),
      octree_(o.octree_),
      luminance_floor_(o.luminance_floor_),
      light_scales_(o.light_scales_) {}

std::unique_ptr<IrradianceCache> IrradianceCache::clone() const { return std::unique_ptr<IrradianceCache>(new IrradianceCache(*this)); }

bool IrradianceCache::made_like(const Bounds& scene_bounds, const CacheSettings& settings, bool ao_only) const {
    return scene_bounds.lo == scene_bounds_.lo && scene_bounds.hi == scene_bounds_.hi && settings == settings_ && ao_only == ao_only_;
}

void IrradianceCache::rescale_lights(std::vector<Color> scales) {
    light_scales_ = std::move(scales);
    const auto rescale = [this](std::deque<Record>& records) {
        parallel_for_each_index(size_t(0), records.size(), [&](size_t i) {
            Record& r = records[i];
            if (r.parts && r.parts->light.size() == light_scales_.size())
                apply_light_scales(r, light_scales_);
            else
                r.parts.reset();
        });
    };
    rescale(records_);
    rescale(fragment_records_);
    records_changed();
}

std::span<const FilteredValue> IrradianceCache::filtered_values() const {
    if (!(settings_.record_filter > 0)) return {};
    Filtered& f = *filtered_;
    if (!f.ready.load(std::memory_order_acquire)) {
        std::lock_guard lock(f.mutex);
        if (!f.ready.load(std::memory_order_relaxed)) {
            // Isolated: a thread of the filter's loop must not pick up an outer task (a tile
            // of lookups) that would wait for this very lock.
            tbb::this_task_arena::isolate([&] { f.values = filter_record_values(*this, settings_.record_filter); });
            f.ready.store(true, std::memory_order_release);
        }
    }
    return f.values;
}

bool IrradianceCache::misses(const Vec3& p, const Vec3& n, std::span<const Record> extra, float own, float min_weight) const {
    // A record at p itself (weight 1 there, 0.99 for float rounding) covers p whatever
    // min_weight says: above 1 no single record could, and a fragment that made a record would
    // miss again on every re-render from the cache.
    // Once the weights reach min_weight the answer is known (no miss): the walk ends there,
    // which is where most fragments of the later sub-passes stand.
    const float enough = min_weight > 0 ? min_weight : settings_.min_weight;
    float sum = 0, top = 0;
    auto add = [&](const float w) {
        sum += w, top = std::max(top, w);
        return sum >= enough;
    };
    octree_.visit_until(p, [&](uint32_t id) { return add(record_weight(shapes_[id], p, n, metric_)); });
    if (sum >= enough) return false;
    for (const Record& r : extra)
        if (add(record_weight(r, p, n, metric_))) return false;
    return top < own;
}

bool IrradianceCache::has_light_parts(size_t lights) const {
    const auto has = [lights](const Record& r) { return r.parts && r.parts->light.size() == lights; };
    return std::all_of(records_.begin(), records_.end(), has) && std::all_of(fragment_records_.begin(), fragment_records_.end(), has);
}

void IrradianceCache::set_values(Record& r, const GatherResult& g, bool gradients, float grad_t_scale) const {
    r.ao = g.ao;
    r.set_bins(g.bins);  // with light parts, the signal's (every light at scale 1)
    r.cells = g.cells, r.cell_hits = g.cell_hits, r.grid = g.grid;
    r.guide = g.guide;
    // Capped (a record in near darkness divides by almost nothing): past 1000 % it is all
    // noise anyway, and a cache file refuses values beyond 1e20.
    r.noise = g.rel_stderr >= 0 && g.rel_stderr < 1e3f ? g.rel_stderr : 1e3f;
    r.bent = g.bent_normal;
    r.ao_grad_r = gradients ? g.ao_grad_rot : Vec3(0);
    r.ao_grad_t = gradients ? g.ao_grad_trans * grad_t_scale : Vec3(0);
    if (!g.parts) {
        r.E = g.irradiance, r.dir = g.light_dir;
        r.grad_r = r.grad_t = {};
        if (!gradients) return;
        r.grad_r = g.grad_rot;
        for (size_t c = 0; c < 3; ++c) r.grad_t[c] = g.grad_trans[c] * grad_t_scale;
        return;
    }
    if (light_scales_.size() != g.parts->light.size()) throw std::logic_error("irradiance cache: light scales not set");
    auto parts = std::make_shared<LightParts>(*g.parts);
    const auto adjust = [&](LightPart& part) {
        if (!gradients) part.grad_r = part.grad_t = {};
        for (Vec3& gt : part.grad_t) gt = gt * grad_t_scale;
    };
    adjust(parts->signal);
    for (LightPart& part : parts->light) adjust(part);
    r.parts = std::move(parts);
    apply_light_scales(r, light_scales_);
}

Interpolated IrradianceCache::lookup(const Vec3& p, const Vec3& n, bool shading, const Vec3* at_p, const Vec3* at_n) const {
    const CacheSettings& s = shading ? shading_settings_ : settings_;
    const RecordMetric& metric = shading ? shading_metric_ : metric_;
    Interpolated out;
    // Weighted mean of differences from the first contributing record's value: a constant
    // field comes back bit-exact, not rounded by sum(w E) / sum(w).
    bool first = true;
    Color base(0);
    float base_ao = 0;
    double de[3] = {0, 0, 0}, dao = 0, wsum = 0, lsum = 0, l2sum = 0, w2sum = 0, nsum = 0, own = 0;
    Vec3 bent(0);
    std::array<Vec3, 3> dir{};
    // The shading pass reads the records' filtered values (record_filter.h) when there are.
    const std::span<const FilteredValue> filtered = shading ? filtered_values() : std::span<const FilteredValue>();
    octree_.visit(p, [&](uint32_t id) {
        float w = record_weight(shapes_[id], p, n, metric);
        if (w <= 0) return;
        const Record& r = records_[id];
        const Color& E = filtered.empty() ? r.E : filtered[id].E;
        const float ao = filtered.empty() ? r.ao : filtered[id].ao;
        Color ei = E;
        float ai = ao;
        // The spread decides refinement: with light parts it is the signal's, which no light's
        // colour or intensity changes.
        const LightPart* signal = r.parts ? &r.parts->signal : nullptr;
        Color si = signal ? signal->E : Color(0);
        if (settings_.gradients) {
            const Vec3 dp = (at_p ? *at_p : p) - r.p, rot = cross(r.n, at_n ? *at_n : n);
            // AO records hold no light (E, its directions and gradients are 0): nothing to extrapolate.
            if (!ao_only_) ei = extrapolated(E, r.grad_t, r.grad_r, dp, rot);
            if (signal) si = extrapolated(signal->E, signal->grad_t, signal->grad_r, dp, rot);
            ai = extrapolated_ao(ao, r.ao_grad_t, r.ao_grad_r, dp, rot);
        }
        if (first) base = ei, base_ao = ai, first = false;
        if (!ao_only_)
            for (int c = 0; c < 3; ++c) de[c] += static_cast<double>(w) * (ei[c] - base[c]);
        dao += static_cast<double>(w) * (ai - base_ao);
        const double l = ao_only_ ? ai : luminance(signal ? si : ei);
        lsum += w * l;
        l2sum += w * l * l;
        wsum += w;
        w2sum += static_cast<double>(w) * w;
        nsum += w * (r.noise * l) * (r.noise * l);
        // A refined fragment's own gather is as noisy as a record's at its rays (refine_rays).
        const double own_rays = s.refine_rays > 0 ? s.refine_rays : std::max<double>(r.rays, 1);
        own += w * (r.noise * l) * (r.noise * l) * std::max<double>(r.rays, 1) / own_rays;
        bent += r.bent * w;
        if (!ao_only_)
            for (size_t c = 0; c < 3; ++c) dir[c] += r.dir[c] * w;
        ++out.records;
    });
    out.weight = static_cast<float>(wsum);
    if (wsum <= 0) {
        out.bent = n;
        return out;
    }
    for (int c = 0; c < 3; ++c) out.E[c] = base[c] + static_cast<float>(de[c] / wsum);
    out.ao = base_ao + static_cast<float>(dao / wsum);
    const double mean = lsum / wsum;
    double var = std::max(0.0, l2sum / wsum - mean * mean);
    // Less what the records' own noise alone would spread them by: the expected weighted sample
    // variance of independent estimates of one value, sum(w s^2)/W (1 - sum(w^2)/W^2).
    var = std::max(0.0, var - settings_.refine_noise * (nsum / wsum) * (1 - w2sum / (wsum * wsum)));
    // A fragment's own gather pays only where the records' bias is more than the noise it would
    // bring beyond the interpolation's own (sum(w^2 s^2)/W^2 of independent records): with few
    // rays per record refinement made the error worse (Cornell box, 128 rays: 8.36 % against
    // 8.17 % without it). Judged on what is left over.
    if (settings_.refine_noise > 0)
        var = std::max(0.0, var - settings_.refine_noise * std::max(0.0, own / wsum - (nsum / wsum) * (w2sum / (wsum * wsum))));
    const double floor = ao_only_ ? 1e-3 : std::max<double>(luminance_floor_, 1e-12);
    out.spread = static_cast<float>(std::sqrt(var) / std::max(mean, floor));
    auto inv = static_cast<float>(1 / wsum);
    for (size_t c = 0; c < 3; ++c) out.dir[c] = dir[c] * inv;
    out.bent = dot(bent, bent) > 0 ? normalize(bent) : n;
    return out;
}

void IrradianceCache::light_shares(const Vec3& p, const Vec3& n, bool shading, const Vec3* at_p, const Vec3* at_n,
                                   std::span<Color> out) const {
    const RecordMetric& m = shading ? shading_metric_ : metric_;
    std::fill(out.begin(), out.end(), Color(0));
    octree_.visit(p, [&](uint32_t id) {
        const float w = record_weight(shapes_[id], p, n, m);
        if (w <= 0) return;
        const Record& r = records_[id];
        if (!r.parts || r.parts->light.size() != out.size()) return;
        const Vec3 dp = (at_p ? *at_p : p) - r.p, rot = cross(r.n, at_n ? *at_n : n);
        for (size_t i = 0; i < out.size(); ++i) {
            const LightPart& part = r.parts->light[i];
            const Color e = settings_.gradients ? extrapolated(part.E, part.grad_t, part.grad_r, dp, rot) : part.E;
            out[i] += e * light_scales_[i] * w;
        }
    });
    normalise_shares(out);
}

Record IrradianceCache::make_record(const GatherResult& g, const Vec3& p, const Vec3& n, float footprint, uint64_t key) const {
    Record r;
    r.p = p;
    r.n = n;
    r.footprint = footprint;
    r.harmonic = g.harmonic_distance;
    r.dmin = g.min_distance;
    r.key = key;
    r.rays = static_cast<uint32_t>(g.rays);
    r.origin = p;
    r.reach = g.reach;
    // TL04: half the minimum qualifying distance; Ward: the harmonic mean.
    r.raw_radius = settings_.metric == Metric::Ward ? g.harmonic_distance : settings_.radius_scale * g.min_distance;
    const float rmin = settings_.min_spacing * footprint, rmax = settings_.max_spacing * footprint;
    r.radius = std::clamp(r.raw_radius, rmin, rmax);
    if (settings_.metric == Metric::Hessian) {
        // Radii where the second-order change reaches hessian_error: e = lambda r^2 / 2.
        auto radius_for = [&](float lambda) { return lambda > 0 ? std::sqrt(2 * settings_.hessian_error / lambda) : INFINITY; };
        r.raw_radius = radius_for(g.hess_fast);
        r.radius = std::clamp(r.raw_radius, rmin, rmax);
        set_long_radius(r, radius_for(g.hess_slow), g.hess_axis);
    }
    // A radius raised to the minimum spacing reaches further than the gather measured its
    // gradient for (ic-algorithms.md 2.4, Mitsuba's cap): the translational gradient is scaled
    // by raw / R_min there, so extrapolation over R_min changes the value as over the raw radius.
    float grad_t_scale = raised_share(r.raw_radius, rmin);
    // Weber's law: the distance at which the gradient-extrapolated change reaches tau times
    // the record's value (luminance, or AO), never below the minimum spacing. (With light
    // parts, g's values are the signal's: every light at scale 1.)
    if (settings_.gradient_limit > 0) {
        float value, slope;
        if (ao_only_) {
            value = std::max(g.ao, 0.01f);
            slope = length(g.ao_grad_trans);
        } else {
            Vec3 gy = g.grad_trans[0] * 0.2126f + g.grad_trans[1] * 0.7152f + g.grad_trans[2] * 0.0722f;
            value = std::max(luminance(g.irradiance), std::max(luminance_floor_, 1e-12f));
            slope = length(gy);
        }
        float weber = slope > 0 ? settings_.gradient_limit * value / slope : INFINITY;
        if (weber < rmin) {
            // The limit would pack records closer than the minimum spacing (corners, where
            // 1/r terms make gradients explode): keep the spacing and scale the translational
            // gradient instead, so extrapolation over R_min changes the value by at most tau E.
            grad_t_scale = std::min(grad_t_scale, weber / rmin);
            weber = rmin;
        }
        r.weber = weber;
    }
    set_values(r, g, true, grad_t_scale);
    return r;
}

void IrradianceCache::clamp_to_neighbours(Record& r, std::span<const Record> extra) const {
    if (!settings_.neighbour_clamp || !std::isfinite(r.raw_radius)) return;
    float raw = r.raw_radius;
    auto limit = [&](const Record& o) {
        float d = length(o.p - r.p);
        if (d < o.support && dot(o.n, r.n) > 0) raw = std::min(raw, o.raw_radius + d);
    };
    octree_.visit(r.p, [&](uint32_t id) { limit(records_[id]); });
    for (const Record& o : extra) limit(o);
    set_raw_radius(r, raw, std::clamp(raw, settings_.min_spacing * r.footprint, settings_.max_spacing * r.footprint));
    if (r.radius_long > 0) set_long_radius(r, r.radius_long, r.axis);
}

void IrradianceCache::set_raw_radius(Record& r, float raw, float radius) const {
    // Below the minimum spacing the record is kept at it, further than its raw radius: its
    // translational gradient is capped as a raw radius that short is at creation (raw / R_min).
    const float rmin = settings_.min_spacing * r.footprint;
    if (const float before = raised_share(r.raw_radius, rmin), after = raised_share(raw, rmin); after < before && before > 0)
        scale_translational_gradient(r, after / before);
    r.raw_radius = raw, r.radius = radius;
}

void IrradianceCache::scale_translational_gradient(Record& r, float factor) const {
    r.ao_grad_t = r.ao_grad_t * factor;
    if (!r.parts) {
        for (Vec3& g : r.grad_t) g = g * factor;
        return;
    }
    auto parts = std::make_shared<LightParts>(*r.parts);  // a fresh record's own: not shared yet
    for (Vec3& g : parts->signal.grad_t) g = g * factor;
    for (LightPart& part : parts->light)
        for (Vec3& g : part.grad_t) g = g * factor;
    r.parts = std::move(parts);
    apply_light_scales(r, light_scales_);
}

void IrradianceCache::set_long_radius(Record& r, float wanted, const Vec3& axis) const {
    const float cap = std::min(settings_.max_anisotropy * r.radius, settings_.max_spacing * r.footprint);
    r.radius_long = std::clamp(wanted, r.radius, std::max(r.radius, cap));
    r.axis = r.radius_long > r.radius ? axis : Vec3(0);
    if (r.radius_long <= r.radius) r.radius_long = 0;
}

uint32_t IrradianceCache::insert(Record r) {
    clamp_to_neighbours(r);
    return insert_loaded(std::move(r));
}

uint32_t IrradianceCache::insert_loaded(Record r) {
    records_changed();
    r.support = support(r);
    auto id = static_cast<uint32_t>(records_.size());
    shapes_.emplace_back(r);
    octree_.insert(id, r.p, r.support);
    records_.push_back(std::move(r));
    return id;
}

void IrradianceCache::insert_fragment_record(const Record& r) {
    if (fragment_index_.emplace(r.key, static_cast<uint32_t>(fragment_records_.size())).second) fragment_records_.push_back(r);
}

void IrradianceCache::replace_fragment_record(const Record& r) {
    auto [it, added] = fragment_index_.emplace(r.key, static_cast<uint32_t>(fragment_records_.size()));
    if (added)
        fragment_records_.push_back(r);
    else
        fragment_records_[it->second] = r;
}

const Record* IrradianceCache::fragment_record(uint64_t key, const Vec3& p) const {
    auto it = fragment_index_.find(key);
    if (it == fragment_index_.end()) return nullptr;
    const Record& r = fragment_records_[it->second];
    return r.p.x == p.x && r.p.y == p.y && r.p.z == p.z ? &r : nullptr;
}

CacheFile IrradianceCache::to_file(const CacheFileInfo& info) const {
    CacheFile f;
    f.info = info;
    f.info.luminance_floor = luminance_floor_;
    f.records.assign(records_.begin(), records_.end());
    f.fragment_records.assign(fragment_records_.begin(), fragment_records_.end());
    return f;
}

size_t IrradianceCache::memory_bytes() const {
    size_t parts = 0;  // light parts: per record (copies share them only across caches)
    for (const auto* list : {&records_, &fragment_records_})
        for (const Record& r : *list) parts += r.parts ? r.parts->bytes() : 0;
    return parts + (records_.size() + fragment_records_.size()) * sizeof(Record) + shapes_.size() * sizeof(RecordShape) +
           octree_.memory_bytes() + fragment_index_.size() * (sizeof(uint64_t) + sizeof(uint32_t) + 2 * sizeof(void*));
}

}  // namespace bounce
