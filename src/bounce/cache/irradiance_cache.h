// The irradiance cache: records in a spatial index, interpolation with gradients under the
// combined, normalised error metrics, and record creation from a gather. Lookups are safe from
// any number of threads while nobody inserts; the passes (passes.h) insert between sub-passes.
#pragma once

#include <atomic>
#include <deque>
#include <memory>
#include <mutex>
#include <shared_mutex>
#include <span>
#include <unordered_map>

#include "bounce/cache/cache_file.h"
#include "bounce/cache/octree.h"
#include "bounce/cache/record.h"
#include "bounce/gather/gather.h"

namespace bounce {

/// What interpolation returns at a point.
struct Interpolated {
    Color E{0};
    float ao = 1;
    Vec3 bent{0, 0, 1};
    std::array<Vec3, 3> dir{};
    float weight = 0;  ///< sum of the weights (0 = no record applies)
    int records = 0;   ///< how many records contributed
    /// How much the contributing records disagree at this point: the weighted standard
    /// deviation of their extrapolated luminance (AO in AO mode) over the weighted mean, less
    /// CacheSettings::refine_noise times what their own noise (Record::noise) would give.
    float spread = 0;
};

class IrradianceCache {
  public:
    IrradianceCache(const Bounds& scene_bounds, CacheSettings settings, bool ao_only);
    IrradianceCache(IrradianceCache&&) = default;
    IrradianceCache& operator=(IrradianceCache&&) = default;

    /// A copy of the records, the spatial index, the light scales and the luminance floor (with
    /// a lock of its own): what inserting every record into a new cache would give, without
    /// re-inserting them.
    std::unique_ptr<IrradianceCache> clone() const;
    /// Whether a cache made with these arguments would index and weigh records as this one (so
    /// clone() may stand for it).
    bool made_like(const Bounds& scene_bounds, const CacheSettings& settings, bool ao_only) const;
    /// Sets the light scales and every record's values from its light parts at them; a record
    /// whose parts are not for as many lights loses them (CacheSettings::light_parts).
    void rescale_lights(std::vector<Color> scales);

    const CacheSettings& settings() const { return settings_; }
    bool ao_only() const { return ao_only_; }
    size_t size() const { return records_.size(); }
    const Record& record(size_t i) const { return records_[i]; }

    /// Interpolates at (p, n). The result's weight is 0 when no record applies. `shading`
    /// uses the shading pass's longer reach (CacheSettings::shading_reach).
    /// `at_p`, `at_n` (default p, n): where the gradients extrapolate each record's value to,
    /// when records are looked up on another surface (the displaced point and normal of a
    /// fragment whose records live on the un-displaced surface).
    Interpolated lookup(const Vec3& p, const Vec3& n, bool shading = false, const Vec3* at_p = nullptr, const Vec3* at_n = nullptr) const;
    /// Each light's share of that interpolation (records need light parts): light i's part of
    /// every record, times its scale, weighed and extrapolated as lookup does the value, then
    /// divided per channel by the lights' sum, so the shares sum to 1 (0 where there is no
    /// light). `out`: one entry per light.
    void light_shares(const Vec3& p, const Vec3& n, bool shading, const Vec3* at_p, const Vec3* at_n, std::span<Color> out) const;
    /// Calls f(id, weight) for every record whose support holds p (weight 0 when rejected);
    /// `shading`: the shading pass's weights (CacheSettings::shading_reach).
    template <typename F>
    void visit_weights(const Vec3& p, const Vec3& n, F&& f, bool shading = false) const {
        const RecordMetric& m = shading ? shading_metric_ : metric_;
        octree_.visit(p, [&](uint32_t id) { f(id, record_weight(shapes_[id], p, n, m)); });
    }
    /// The records' values as the shading pass reads them: filtered in record space
    /// (CacheSettings::record_filter, record_filter.h), made on the first call after the
    /// records last changed; empty when the filter is off. Call it once before a parallel
    /// loop of lookups (the first call filters every record).
    std::span<const FilteredValue> filtered_values() const;
    /// True when a lookup at (p, n) would miss: the weights of this cache's records and of
    /// `extra` (a tile's private records) sum below min_weight, and none of them sits at p.
    /// `own` (default 0.99): a record whose weight reaches it sits at p and covers it alone;
    /// `min_weight` (default: the settings'): the sum below which a lookup misses.
    bool misses(const Vec3& p, const Vec3& n, std::span<const Record> extra = {}, float own = 0.99f, float min_weight = -1) const;

    /// Turns a gather at (p, n) into a record: radius from the qualifying minimum distance
    /// (TL04) or the harmonic mean (Ward) clamped to [min_spacing, max_spacing] pixels of
    /// `footprint`, and the Weber distance of the gradient limit.
    Record make_record(const GatherResult& g, const Vec3& p, const Vec3& n, float footprint, uint64_t key) const;
    /// r's irradiance, AO, bent normal, light directions and (with `gradients`) gradients from
    /// gather g, the translational ones times `grad_t_scale`; with light parts, the parts are
    /// kept and the values are their sum at the cache's light scales.
    void set_values(Record& r, const GatherResult& g, bool gradients = true, float grad_t_scale = 1) const;
    /// CacheSettings::light_parts: what each light's part is multiplied by (light_scales).
    void set_light_scales(std::vector<Color> scales) { light_scales_ = std::move(scales); }
    const std::vector<Color>& light_scales() const { return light_scales_; }
    /// Whether every record keeps its light parts, for `lights` lights (a rescale is exact).
    bool has_light_parts(size_t lights) const;
    /// Neighbour clamping (Krivanek et al. 2006): R_r <= R_j + |p_r - p_j| on the unclamped radii
    /// over this cache's records and `extra` whose reach includes p_r; then the screen-space
    /// clamps again. A no-op when the setting is off.
    void clamp_to_neighbours(Record& r, std::span<const Record> extra = {}) const;
    /// Gives a new record `raw` and `radius` (a neighbour clamp's, or the ones an earlier frame's
    /// record kept): a raw radius lowered below the minimum spacing caps the translational
    /// gradient by raw / R_min, as at creation.
    void set_raw_radius(Record& r, float raw, float radius) const;
    /// Multiplies r's translational gradients (irradiance, AO, every light part's) by `factor`.
    void scale_translational_gradient(Record& r, float factor) const;
    /// Hessian records: the long radius along `axis`, between the short radius and
    /// max_anisotropy times it (and the maximum spacing); round (0) when it is not longer.
    void set_long_radius(Record& r, float wanted, const Vec3& axis) const;
    /// Distance beyond which `r` has no weight in any lookup of this cache (Record::support).
    float support(const Record& r) const { return record_support(r, shading_settings_); }
    /// Inserts (not thread-safe: hold mutex() exclusively while others may read); applies
    /// neighbour clamping first. Returns the record's index.
    uint32_t insert(Record r);

    /// Inserts a record read from a file as it is (no clamping: its radius is final).
    uint32_t insert_loaded(Record r);

    /// Per-fragment refinement's records: one fragment's own gather (Record::key names the
    /// fragment, Record::p is its point), outside the spatial index, so no lookup uses it.
    /// Inserting a key twice keeps the first.
    void insert_fragment_record(const Record& r);
    /// The same, but a record of the key already there is replaced: this frame's fragment at a
    /// pixel supersedes an earlier frame's, whose point it no longer is (frames of a shot).
    void replace_fragment_record(const Record& r);
    /// The record of the fragment with creation key `key` whose point is exactly `p` (a
    /// record kept from another deep buffer does not match), or nullptr.
    const Record* fragment_record(uint64_t key, const Vec3& p) const;
    size_t fragment_record_count() const { return fragment_records_.size(); }
    const Record& fragment_record_at(size_t i) const { return fragment_records_[i]; }
    /// Records and header information for a cache file.
    CacheFile to_file(const CacheFileInfo& info) const;
    float luminance_floor() const { return luminance_floor_; }

    size_t memory_bytes() const;
    /// The reader-writer lock of the cache's users (the passes): lookups hold it shared, inserts
    /// exclusively. The cache itself does not take it, so one lock covers a whole tile.
    std::shared_mutex& mutex() const { return *mutex_; }
    /// Floor under the record value in the Weber metric (E -> 0 in black surroundings would make
    /// every gradient look infinite); the passes set it to 1e-3 of the first sub-pass's mean.
    void set_luminance_floor(float f) { luminance_floor_ = f; }

  private:
    IrradianceCache(const IrradianceCache& other);  ///< clone()
    Bounds scene_bounds_;
    CacheSettings settings_, shading_settings_;
    RecordMetric metric_, shading_metric_;  ///< what the weights read of the two
    bool ao_only_;
    std::deque<Record> records_;
    std::vector<RecordShape> shapes_;  ///< records_[i]'s shape, packed for the lookups' weights
    std::deque<Record> fragment_records_;
    std::unordered_map<uint64_t, uint32_t> fragment_index_;  ///< key -> fragment_records_ index
    RecordOctree octree_;
    float luminance_floor_ = -1;                                                        ///< Weber floor, fixed from the first record batch
    std::vector<Color> light_scales_;                                                   ///< light_parts: per scene light
    std::unique_ptr<std::shared_mutex> mutex_ = std::make_unique<std::shared_mutex>();  // keeps the cache movable
    /// filtered_values(): made once per state of the records (reset by every change).
    struct Filtered {
        std::mutex mutex;
        std::atomic<bool> ready{false};
        std::vector<FilteredValue> values;
    };
    std::unique_ptr<Filtered> filtered_ = std::make_unique<Filtered>();
    void records_changed() { filtered_->ready = false; }
};

}  // namespace bounce
