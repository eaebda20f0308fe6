#include "bounce/cache/temporal.h"
#include "bounce/cache/sites.h"

#include <algorithm>
#include <cmath>

#include "bounce/core/parallel.h"

namespace bounce {

namespace {

/// Each direction bin of a gather as a cone in the gather's frame (z = normal): the axis through
/// the middle of its elevation band and azimuth sector, and the angle to its farthest corner.
struct BinCone {
    Vec3 axis;
    float cos_half;  ///< cosine of the half-angle (a margin added)
};

const std::array<BinCone, kReachBins>& bin_cones() {
    static const std::array<BinCone, kReachBins> cones = [] {
        std::array<BinCone, kReachBins> out{};
        const auto dir = [](float sin2, float phi) {
            const float s = std::sqrt(sin2), c = std::sqrt(std::max(0.0f, 1 - sin2));
            return Vec3{s * std::cos(phi), s * std::sin(phi), c};
        };
        for (int b = 0; b < kReachBands; ++b)
            for (int k = 0; k < kReachSectors; ++k) {
                const float s0 = static_cast<float>(b) / kReachBands, s1 = static_cast<float>(b + 1) / kReachBands;
                const float p0 = 2 * kPi * static_cast<float>(k) / kReachSectors, p1 = 2 * kPi * static_cast<float>(k + 1) / kReachSectors;
                const Vec3 axis = normalize(dir(0.5f * (s0 + s1), 0.5f * (p0 + p1)));
                float cos_half = 1;
                // The corners and edge midpoints bound the cell's angular extent.
                for (float sin2 : {s0, 0.5f * (s0 + s1), s1})
                    for (float phi : {p0, 0.5f * (p0 + p1), p1}) cos_half = std::min(cos_half, dot(axis, dir(sin2, phi)));
                const float half = std::acos(std::clamp(cos_half, -1.0f, 1.0f)) + 0.05f;  // ~3 degrees of margin
                out[static_cast<size_t>(b * kReachSectors + k)] = {axis, std::cos(std::min(half, kPi))};
            }
        return out;
    }();
    return cones;
}

/// Rotates and moves a record with its object's rigid motion.
void move_rigidly(Record& r, const Transform& delta) {
    const auto turn = [&](Vec3& v) { v = delta.vector(v); };
    r.p = delta.point(r.p), r.origin = delta.point(r.origin);
    r.n = normalize(delta.vector(r.n));
    turn(r.bent);
    r.bent = normalize(r.bent);
    for (size_t c = 0; c < 3; ++c) turn(r.dir[c]), turn(r.grad_r[c]), turn(r.grad_t[c]);
    turn(r.ao_grad_r), turn(r.ao_grad_t);
    if (r.radius_long > 0) r.axis = normalize(delta.vector(r.axis));
}

/// A triangle's orthonormal frame (first edge, then in-plane, then normal) as columns.
std::array<Vec3, 3> triangle_frame(const Vec3& a, const Vec3& b, const Vec3& c) {
    const Vec3 e = normalize(b - a), n = normalize(cross(b - a, c - a));
    return {e, cross(n, e), n};
}

std::array<Vec3, 3> triangle_of(const TriangleMesh& m, uint32_t t) {
    return {m.positions[m.indices[3 * t]], m.positions[m.indices[3 * t + 1]], m.positions[m.indices[3 * t + 2]]};
}

/// Moves a record on a deforming object with its triangle: to its barycentrics on the new
/// triangle, every direction turned as the triangle turned. False if it cannot (another mesh).
bool move_on_surface(Record& r, const TriangleMesh& was, const TriangleMesh& now) {
    if (r.anchor_prim == kNoAnchor || r.anchor_prim >= was.triangle_count() || r.anchor_prim >= now.triangle_count()) return false;
    const auto t0 = triangle_of(was, r.anchor_prim), t1 = triangle_of(now, r.anchor_prim);
    const auto f0 = triangle_frame(t0[0], t0[1], t0[2]), f1 = triangle_frame(t1[0], t1[1], t1[2]);
    if (!isfinite(f0[2]) || !isfinite(f1[2])) return false;
    const auto turn = [&](const Vec3& v) {  // into the old frame, out of the new one
        return f1[0] * dot(v, f0[0]) + f1[1] * dot(v, f0[1]) + f1[2] * dot(v, f0[2]);
    };
    const Vec3 offset = turn(r.origin - r.p);
    r.p = t1[0] + (t1[1] - t1[0]) * r.anchor_p.x + (t1[2] - t1[0]) * r.anchor_p.y;
    r.origin = r.p + offset;
    r.n = normalize(turn(r.n)), r.bent = normalize(turn(r.bent));
    for (size_t c = 0; c < 3; ++c) r.dir[c] = turn(r.dir[c]), r.grad_r[c] = turn(r.grad_r[c]), r.grad_t[c] = turn(r.grad_t[c]);
    r.ao_grad_r = turn(r.ao_grad_r), r.ao_grad_t = turn(r.ao_grad_t);
    if (r.radius_long > 0) r.axis = normalize(turn(r.axis));
    return true;
}

/// The record's reach for this camera: what a record gathered here now would get, its measured
/// (and neighbour-clamped) world radius clamped to the minimum and maximum spacing in this
/// view's pixels. (Keeping the radius of the view that made it, raised to the new minimum only,
/// left records spaced for a far camera bleeding across edges as it came closer: shot A's
/// error 5.83 % against 5.24 % with this rule, docs/animation.md.)
void respace(Record& r, const CameraRays& camera, const CacheSettings& s) {
    const Vec3 d = r.p - camera.origin();
    const float t = length(d);
    if (!(t > 0)) return;
    const float fp = camera.footprint(d / t, t, r.n);
    if (!(fp > 0) || !std::isfinite(fp)) return;
    const float before = r.radius;
    r.footprint = fp;
    r.radius = std::clamp(r.raw_radius, s.min_spacing * fp, s.max_spacing * fp);
    if (r.radius_long > 0) r.radius_long = std::max(r.radius, r.radius_long * r.radius / before);
}

/// How far `r`'s irradiance (relative to it) may have moved this frame.
float drift_bound(const Record& r, const SceneChanges& changes, std::span<const LightChange> light, float brightest, float floor,
                  bool ao_only) {
    double bound = 0;
    for (size_t o = 0; o < changes.objects.size(); ++o) {
        const ObjectMotion& m = changes.objects[o];
        if (m.kind == ObjectMotion::Kind::Static || o == r.anchor || !record_sees(r, m.swept)) continue;
        // An object moving through the view can show or hide at most the brightest radiance
        // over its swept solid angle (AO: that fraction of the cosine-weighted hemisphere).
        bound += static_cast<double>(ao_only ? kInvPi : brightest) * solid_angle_bound(r.origin, m.swept);
    }
    if (!ao_only)
        for (const LightChange& c : light)
            if (record_sees(r, c.bounds)) bound += static_cast<double>(c.delta) * solid_angle_bound(r.origin, c.bounds);
    const double value = ao_only ? std::max(r.ao, 0.01f) : std::max(luminance(r.E), floor);
    return static_cast<float>(bound / value);
}

bool sees_sky(const Record& r) {
    return std::any_of(r.reach.begin(), r.reach.end(), [](float d) { return !std::isfinite(d); });
}

/// A record with its hits: does anything its rays found change this frame? None of its rays
/// passes through a moving object's swept bounds, no hit is on a changed side, no escaped ray
/// sees a changed sky.
bool hits_unchanged(const Record& r, const Scene& now, uint64_t seed, const SceneChanges& changes, const std::vector<Bounds>& boxes,
                    const std::vector<uint64_t>& changed_sides) {
    const GatherHits& h = *r.hits;
    for (size_t c = 0; c < h.t.size(); ++c) {
        if (h.object[c] == kNoHit) {
            if (changes.sky) return false;
            continue;
        }
        const uint64_t object = static_cast<uint64_t>(h.object[c] & ~GatherHits::kHairBit) << 32;
        if (std::binary_search(changed_sides.begin(), changed_sides.end(), object | h.prim[c]) ||
            std::binary_search(changed_sides.begin(), changed_sides.end(), object | LightChange::kEveryTriangle))
            return false;
    }
    if (boxes.empty()) return true;
    std::vector<uint32_t> cells;
    cells_through(GatherGrid{h.m, h.n}, r.origin, r.n, record_stream(r, seed, now.camera.width), h, boxes, cells);
    return cells.empty();
}

}  // namespace

bool record_sees(const Record& r, const Bounds& box) {
    if (box.empty()) return false;
    const Vec3 c = (box.lo + box.hi) * 0.5f, v = c - r.origin;
    const float rad = 0.5f * length(box.hi - box.lo), d = length(v);
    if (d <= rad) return true;
    const Frame frame(r.n);
    const float sin_sub = rad / d, cos_sub = std::sqrt(std::max(0.0f, 1 - sin_sub * sin_sub));
    const Vec3 u = v / d;
    const auto& cones = bin_cones();
    for (size_t b = 0; b < cones.size(); ++b) {
        if (d - rad > r.reach[b]) continue;
        // Angle between the bin's axis and the sphere's centre, less the sphere's half-angle.
        const float cos_axis = dot(frame.to_world(cones[b].axis), u);
        const float angle = std::acos(std::clamp(cos_axis, -1.0f, 1.0f)) - std::acos(std::clamp(cos_sub, -1.0f, 1.0f));
        if (angle <= std::acos(std::clamp(cones[b].cos_half, -1.0f, 1.0f))) return true;
    }
    return false;
}

float solid_angle_bound(const Vec3& o, const Bounds& box) {
    const Vec3 c = (box.lo + box.hi) * 0.5f;
    const float rad = 0.5f * length(box.hi - box.lo), d = length(c - o);
    if (d <= rad) return 2 * kPi;
    const float s = rad / d;
    return 2 * kPi * (1 - std::sqrt(std::max(0.0f, 1 - s * s)));
}

void anchor_record(Record& r, const Object& obj, uint32_t object, uint32_t prim) {
    r.anchor = object;
    if (!obj.deforms) {
        const Transform back = obj.placement.inverse();
        r.anchor_p = back.point(r.p), r.anchor_n = normalize(back.vector(r.n));
        return;
    }
    const TriangleMesh& m = obj.visible();
    if (prim >= m.triangle_count()) return;
    // Barycentrics of p projected onto the triangle.
    const auto t = triangle_of(m, prim);
    const Vec3 e1 = t[1] - t[0], e2 = t[2] - t[0], d = r.p - t[0];
    const float d11 = dot(e1, e1), d12 = dot(e1, e2), d22 = dot(e2, e2), det = d11 * d22 - d12 * d12;
    if (!(std::abs(det) > 0)) return;
    const float b1 = (d22 * dot(d, e1) - d12 * dot(d, e2)) / det, b2 = (d11 * dot(d, e2) - d12 * dot(d, e1)) / det;
    r.anchor_prim = prim, r.anchor_p = {b1, b2, 0};
}

std::vector<Bounds> moving_bounds(const SceneChanges& changes, uint32_t except) {
    std::vector<Bounds> out;
    for (size_t o = 0; o < changes.objects.size(); ++o)
        if (changes.objects[o].kind != ObjectMotion::Kind::Static && o != except) out.push_back(changes.objects[o].swept);
    return out;
}

RandomStream record_stream(const Record& r, uint64_t seed, int full_width) {
    const uint64_t pixel = (r.key & ~kBackSideKey) >> 8;
    const auto w = static_cast<uint64_t>(std::max(1, full_width));
    const RandomStream front =
        fragment_stream(seed, static_cast<int>(pixel % w), static_cast<int>(pixel / w), static_cast<uint32_t>(r.key & 0xff));
    return r.key & kBackSideKey ? back_side_stream(front) : front;
}

namespace {

/// What became of a static record between two frames.
enum class Verdict : uint8_t { Keep, Update, View, Light };

/// What decides it: the moving objects' swept bounds and the changed radiosity sides.
struct FrameChange {
    const Scene& now;
    uint64_t seed;
    const SceneChanges& changes;
    std::span<const LightChange> light;
    float brightest, floor, tolerance;
    bool ao_only;
    std::vector<Bounds> boxes;
    std::vector<uint64_t> changed_sides;  ///< (object << 32 | triangle), sorted

    FrameChange(const Scene& now_, uint64_t seed_, const SceneChanges& c, std::span<const LightChange> l, float bright, float floor_,
                const CacheSettings& s, bool ao)
        : now(now_),
          seed(seed_),
          changes(c),
          light(l),
          brightest(bright),
          floor(floor_),
          tolerance(s.temporal_tolerance),
          ao_only(ao),
          boxes(moving_bounds(c)) {
        for (const LightChange& lc : l) changed_sides.push_back((static_cast<uint64_t>(lc.object) << 32) | lc.triangle);
        std::sort(changed_sides.begin(), changed_sides.end());
    }

    /// With its hits: kept unless a ray or a hit changed (Update). Without: kept while its drift
    /// (grown here) stays within the tolerance, else gathered again (View: something moved in
    /// its view; Light: only light changed).
    Verdict verdict(Record& r) const {
        if (r.hits) return hits_unchanged(r, now, seed, changes, boxes, changed_sides) ? Verdict::Keep : Verdict::Update;
        r.drift += drift_bound(r, changes, light, brightest, floor, ao_only);
        bool geometry = false;
        for (size_t o = 0; o < changes.objects.size() && !geometry; ++o)
            geometry = changes.objects[o].kind != ObjectMotion::Kind::Static && record_sees(r, changes.objects[o].swept);
        const bool sky = changes.sky && !ao_only && sees_sky(r);
        if (r.drift <= tolerance && !sky) return Verdict::Keep;
        return geometry ? Verdict::View : Verdict::Light;
    }
};

/// What a judged record is: one of the cache's, a fragment record of refinement (by key), or
/// an earlier refinement gather whose rays refinement may reuse (EarlierGathers).
enum class Role : uint8_t { Record, Fragment, Gather };

/// Sorts the previous frame's records into `out`: kept, moved, stale (and why) or dropped.
struct Judge {
    TemporalJudgement& out;
    const Scene &before, &now;
    const SceneChanges& changes;
    const CacheSettings& s;
    const CameraRays camera;
    const FrameChange& change;

    /// Moves a record with its object; false when it cannot follow (dropped).
    bool follow(Record& r, ObjectMotion::Kind own) const {
        if (own == ObjectMotion::Kind::Static) return true;
        ++out.anchored;
        bool ok = true;
        if (own == ObjectMotion::Kind::Rigid) move_rigidly(r, changes.objects[r.anchor].delta);
        if (own == ObjectMotion::Kind::Deforming)
            ok = move_on_surface(r, before.objects[r.anchor].visible(), now.objects[r.anchor].visible());
        out.anchors_kept += ok;
        return ok;
    }
    ObjectMotion::Kind own_motion(const Record& r) const {
        const bool anchored = r.anchor != kNoAnchor && r.anchor < changes.objects.size();
        return anchored ? changes.objects[r.anchor].kind : ObjectMotion::Kind::Static;
    }
    void judge(Record r, Role role) const {
        // A moving camera's fragments never land on an earlier frame's points again: its
        // fragment records serve only refinement's hold in the next frame, by where they are.
        if (role == Role::Fragment && changes.camera && r.gathered + 1 < now.frame) {
            ++out.dropped;
            return;
        }
        const ObjectMotion::Kind own = own_motion(r);
        if (own != ObjectMotion::Kind::Static) {
            // Refinement's records and gathers stay where their fragments were: dropped.
            if (role != Role::Record || !follow(r, own)) {
                out.dropped += role != Role::Gather;
                return;
            }
            respace(r, camera, s);
            out.stale.push_back(r), out.why.push_back(StaleReason::Moved), ++out.moved;
            return;
        }
        // A still camera leaves a still record's reach as it was: its footprint for this view is
        // the one it was made with (the fragment's), which the camera's own estimate only nears.
        if (role == Role::Record && changes.camera) respace(r, camera, s);
        sort_still(r, role, change.verdict(r));
    }
    /// A record on a still object, by its verdict.
    void sort_still(Record& r, Role role, Verdict v) const {
        if (v == Verdict::Keep) {
            if (role == Role::Gather) return out.earlier_gathers.push_back(r);
            ++out.kept;
            // ... so kept without their hits (reprojection's gathers keep their own:
            // EarlierGathers). A stale one keeps them: refinement updates it from them should a
            // fragment land on its very point after all, and it lives only through this frame.
            if (role == Role::Fragment && changes.camera) r.hits.reset();
            (role == Role::Fragment ? out.fragment_valid : out.valid).push_back(r);
        } else if (role == Role::Fragment && v == Verdict::Update) {
            out.fragment_stale.emplace(r.key, r);  // updated where refinement still wants it
        } else if (role == Role::Record) {
            const StaleReason why = v == Verdict::Update ? StaleReason::Update
                                    : v == Verdict::View ? StaleReason::View
                                                         : StaleReason::Light;
            ++(why == StaleReason::View ? out.view : out.light);
            out.stale.push_back(r), out.why.push_back(why);
        } else {
            out.dropped += role == Role::Fragment;  // refinement gathers its fragments again where it still needs them
        }
    }
    /// Stale records no fragment needed last frame: they follow their objects, then wait.
    void carry_waiting(Record r) const {
        if (!follow(r, own_motion(r))) {
            ++out.dropped;
            return;
        }
        respace(r, camera, s);
        out.stale.push_back(r), out.why.push_back(StaleReason::View);
    }
};

}  // namespace

TemporalJudgement judge_records(const IrradianceCache& previous, std::span<const Record> waiting, std::span<const Record> gathers,
                                const Scene& before, const Scene& now, const SceneChanges& changes, std::span<const LightChange> light,
                                float brightest, uint64_t seed) {
    TemporalJudgement out;
    if (!changes.comparable) {
        out.dropped = previous.size() + waiting.size();
        return out;
    }
    const CacheSettings& s = previous.settings();
    const FrameChange change(now, seed, changes, light, brightest, std::max(previous.luminance_floor(), 1e-12f), s, previous.ao_only());
    const Judge judge{out, before, now, changes, s, CameraRays(now.camera), change};
    for (size_t i = 0; i < previous.size(); ++i) judge.judge(previous.record(i), Role::Record);
    for (size_t i = 0; i < previous.fragment_record_count(); ++i) judge.judge(previous.fragment_record_at(i), Role::Fragment);
    for (const Record& r : gathers) judge.judge(r, Role::Gather);
    for (const Record& r : waiting) judge.carry_waiting(r);
    return out;
}

EarlierGathers::EarlierGathers(std::vector<Record> records, const Bounds& bounds, float reach, bool need_hits)
    : records_(std::move(records)), index_(bounds), reach_(reach), need_hits_(need_hits) {
    // By where each was gathered (a refinement gather's own point).
    for (size_t i = 0; i < records_.size(); ++i)
        index_.insert(static_cast<uint32_t>(i), records_[i].origin, 2 * reach_ * records_[i].footprint);
}

const Record* EarlierGathers::nearest(const Vec3& p, const Vec3& n, float footprint) const {
    const float reach = reach_ * footprint;
    const float cos_max = std::cos(10 * kPi / 180);
    // The nearest, ties to the lowest index: independent of the octree's visiting order.
    const Record* best = nullptr;
    float best_dist = 0;
    uint32_t best_id = 0;
    index_.visit(p, [&](uint32_t id) {
        const Record& r = records_[id];
        const Vec3 d = r.origin - p;
        const float dist = length(d);
        // On this fragment's surface: the same facing, and not off its plane (a step or a rim).
        if ((need_hits_ && !r.hits) || dist >= reach || dot(r.n, n) < cos_max || std::abs(dot(d, n)) > 0.25f * reach) return;
        if (best && (dist > best_dist || (dist == best_dist && id > best_id))) return;
        best = &r, best_dist = dist, best_id = id;
    });
    return best;
}

std::vector<Record> EarlierGathers::lasting(int frame) const {
    std::vector<Record> out;
    for (const Record& r : records_)
        if (frame - r.gathered < kLifespan) out.push_back(r);
    return out;
}

StaleRecords::StaleRecords(std::vector<Record> records, std::vector<StaleReason> why, const Bounds& bounds, const CacheSettings& s,
                           bool ao_only, Redo redo)
    : index_(bounds, s, ao_only), why_(std::move(why)), done_(records.size(), 0), redo_(std::move(redo)) {
    for (const Record& r : records) index_.insert_loaded(r);
}

void StaleRecords::covering(const Vec3& p, const Vec3& n, std::vector<uint32_t>& out) const {
    index_.visit_weights(p, n, [&](uint32_t id, float w) {
        if (w > 0 && !done_[id]) out.push_back(id);
    });
}

std::vector<Record> StaleRecords::redo(const std::vector<uint32_t>& ids, Stats& stats) {
    std::vector<Record> out(ids.size());
    parallel_for_each_index(0, static_cast<int>(ids.size()), [&](int i) {
        const auto k = static_cast<size_t>(i);
        out[k] = redo_(index_.record(ids[k]), why_[ids[k]], stats.local());
    });
    for (uint32_t id : ids) {
        done_[id] = 1;
        const bool from_hits = (why_[id] == StaleReason::Light || why_[id] == StaleReason::Update) && index_.record(id).hits;
        ++(from_hits ? reshaded : regathered);
    }
    return out;
}

std::vector<Record> StaleRecords::waiting() const {
    std::vector<Record> out;
    for (size_t i = 0; i < done_.size(); ++i)
        if (!done_[i]) out.push_back(index_.record(i));
    return out;
}

}  // namespace bounce
