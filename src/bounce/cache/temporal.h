// Records across the frames of a shot (docs/animation.md). Records on a moving object travel
// with it (their anchor) and are gathered again in place. A record that kept its gather's hits
// (a shot with moving objects or lights) is kept exactly when none of its rays passes through a
// moving object's swept bounds and none of its hits is on a re-baked side whose light changed;
// else those rays alone are traced again and every hit re-shaded: the result is the gather a
// fresh frame would make with the record's own random stream. A record without hits (loaded
// from a file) is kept while a bound on how far its irradiance may have moved — its `drift`,
// L x the solid angle of every change its view summary reaches — stays within
// cache.temporal_tolerance, and gathered again after.
#pragma once

#include <functional>
#include <optional>
#include <span>
#include <unordered_map>
#include <vector>

#include "bounce/cache/irradiance_cache.h"
#include "bounce/deep/deep_buffer.h"
#include "bounce/radiosity/radiosity.h"
#include "bounce/scene/changes.h"

namespace bounce {

/// Why a record of the previous frame was not kept as it was.
enum class StaleReason : uint8_t {
    Moved,   ///< its surface moved: repositioned with it, gathered again in place
    View,    ///< something in its view may have moved (no hits kept to tell which rays): gathered again
    Light,   ///< only the light in its view changed: re-shaded from its hits (or gathered again)
    Update,  ///< with its hits: the rays through moving objects' swept bounds traced again, all re-shaded
};

/// What the previous frame's cache becomes at this frame.
struct TemporalJudgement {
    std::vector<Record> valid;                            ///< kept as they were (their reach respaced for this camera)
    std::vector<Record> stale;                            ///< to be redone before they serve
    std::vector<StaleReason> why;                         ///< parallel to stale
    std::vector<Record> fragment_valid;                   ///< per-fragment refinement's records still valid
    std::unordered_map<uint64_t, Record> fragment_stale;  ///< ... to update where refinement still wants them (by key)
    std::vector<Record> earlier_gathers;                  ///< refinement gathers of earlier frames still valid (EarlierGathers)
    size_t kept = 0, moved = 0, view = 0, light = 0, dropped = 0;
    /// Records of the previous frame on objects that moved, and those of them that followed their
    /// anchor to this frame (the rest could not and were dropped).
    size_t anchored = 0, anchors_kept = 0;
};

/// Judges every record of `previous` for this frame: `changes` between the scenes, `light` the
/// radiosity that changed, `brightest` the largest radiance a moving object can show or hide.
/// `waiting` (stale records of earlier frames no fragment needed yet) stay stale, moved with
/// their object; `gathers` (EarlierGathers::lasting) are kept or dropped as fragment records
/// are. Records on a deforming object ride on their triangle from `before`'s mesh to `now`'s
/// (turned with it).
TemporalJudgement judge_records(const IrradianceCache& previous, std::span<const Record> waiting, std::span<const Record> gathers,
                                const Scene& before, const Scene& now, const SceneChanges& changes, std::span<const LightChange> light,
                                float brightest, uint64_t seed);

/// Anchors a new record on object `object` (which moves in the shot): in its own space for a
/// rigid one, at its barycentrics on triangle `prim` of its visible mesh for a deforming one.
void anchor_record(Record& r, const Object& obj, uint32_t object, uint32_t prim);

/// The swept bounds of every object that moved, except object `except`.
std::vector<Bounds> moving_bounds(const SceneChanges& changes, uint32_t except = kNoAnchor);

/// True when a ray of `r`'s gather could reach into `box` (a conservative test of its view
/// summary: per direction bin, a cone up to its farthest hit).
bool record_sees(const Record& r, const Bounds& box);

/// Upper bound on the solid angle `box` subtends from `o` (its bounding sphere's cone).
float solid_angle_bound(const Vec3& o, const Bounds& box);

/// The record's random stream: the one of the fragment that created it (Record::key), in a
/// frame `full_width` pixels wide.
RandomStream record_stream(const Record& r, uint64_t seed, int full_width);

/// Earlier frames' refinement gathers (per-fragment records gathered, with their hits), by where
/// they were gathered. A moving camera never puts a fragment on exactly the point of one
/// before; with CacheSettings::temporal_refine_reuse, a fragment that refinement wants a gather
/// for reuses the rays of the nearest of them on its surface within `reach` of its pixel
/// footprints (Gatherer::reproject): only its near rays are traced again. A reprojected gather
/// is never itself reused (it keeps no hits), and a gather serves kLifespan frames, then its
/// neighbourhood gathers again: memory stays bounded over a shot.
class EarlierGathers {
  public:
    static constexpr int kLifespan = 12;
    /// With `need_hits` false, any record in reach counts (refinement's hold: docs/animation.md).
    EarlierGathers(std::vector<Record> records, const Bounds& bounds, float reach, bool need_hits = true);
    /// The gather nearest (p, n) on its surface (the same facing within 10 degrees, off its plane
    /// by at most a quarter of the reach), or null.
    const Record* nearest(const Vec3& p, const Vec3& n, float footprint) const;
    /// The gathers that still serve at `frame`.
    std::vector<Record> lasting(int frame) const;

  private:
    std::vector<Record> records_;
    RecordOctree index_;
    float reach_;
    bool need_hits_;
};

/// Stale records waiting for a new gather. The gathering pass asks which of them cover each
/// fragment's point; those are redone (by `redo`), and a miss they cover makes no new record.
class StaleRecords {
  public:
    using Redo = std::function<Record(const Record&, StaleReason, Counters&)>;
    StaleRecords(std::vector<Record> records, std::vector<StaleReason> why, const Bounds& bounds, const CacheSettings& s, bool ao_only,
                 Redo redo);
    /// Indices of records not yet redone whose weight at (p, n) is positive.
    void covering(const Vec3& p, const Vec3& n, std::vector<uint32_t>& out) const;
    /// Redoes `ids` (sorted, unique; in parallel) and returns them in that order, marked done.
    std::vector<Record> redo(const std::vector<uint32_t>& ids, Stats& stats);
    /// The records never redone (they wait, unused, for a later frame).
    std::vector<Record> waiting() const;
    size_t regathered = 0, reshaded = 0;

  private:
    IrradianceCache index_;
    std::vector<StaleReason> why_;
    std::vector<uint8_t> done_;
    Redo redo_;
};

}  // namespace bounce
