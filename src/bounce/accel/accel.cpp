#include "bounce/accel/accel.h"

#include <fmt/format.h>

#include <algorithm>
#include <new>
#include <stdexcept>

#include "bounce/accel/parts.h"
#include "bounce/core/memory.h"

namespace bounce {

namespace {
void embree_error(void*, RTCError code, const char* str) {
    if (code == RTC_ERROR_NONE) return;
    if (code == RTC_ERROR_OUT_OF_MEMORY) throw std::bad_alloc();
    throw std::runtime_error(fmt::format("Embree error {}: {}", static_cast<int>(code), str ? str : ""));
}

}  // namespace

namespace {
unsigned ray_mask(const Scene& scene, size_t index, const RayVisibility& to) {
    unsigned mask = (to.camera ? kRayCamera : 0u) | (to.shadows ? kRayShadow : 0u) | (to.indirect ? kRayIndirect : 0u) |
                    (to.reflections ? kRayReflect : 0u);
    for (const Light& l : scene.lights)
        if (l.shadow_slot >= 0 && to.shadows && l.shadowed_by[index]) mask |= kRayShadowLink << l.shadow_slot;
    return mask;
}
}  // namespace

unsigned object_ray_mask(const Scene& scene, size_t index) { return ray_mask(scene, index, scene.objects[index].visible_to); }

unsigned fur_ray_mask(const Scene& scene, size_t index) {
    const Object& o = scene.objects[index];
    return o.fur ? ray_mask(scene, index, o.fur->params.visible_to) : 0u;
}

SceneAccel::SceneAccel(const Scene& scene, const LightingSettings& settings, const SceneAccel* previous) {
    // Refused before Embree allocates: about 100 bytes per triangle and 80 per fur segment
    // and BVH (measured on the ogre and the furry ball), the fine tessellation twice over.
    // A prototype's triangles count once, each placement about 200 bytes of Embree instance.
    double triangles = 0, segments = 0, instances = 0;
    for (const auto& o : scene.objects) {
        triangles +=
            static_cast<double>(o.coarse.triangle_count() + o.fine.triangle_count());  // (none of their own: instances, prototypes)
        if (o.prototype)
            triangles += 2.0 * static_cast<double>(o.local_coarse->triangle_count() + (o.local_fine ? o.local_fine->triangle_count() : 0));
        instances += o.instance ? 1 : 0;
        if (o.fur) segments += 2.0 * static_cast<double>(o.fur->segment_count());
    }
    check_memory(100 * triangles + 80 * segments + 400 * instances, scene.path, "objects",
                 fmt::format("ray tracing {:.3g} triangles, {:.3g} fur segments and {:.3g} instances", triangles, segments / 2, instances));
    // Instances are placements of their prototype's BVH: two levels, as for movers.
    const bool two_level = scene.objects_move() || instances > 0;
    // Parts are the device's: a frame that takes over the previous frame's uses its device.
    if (two_level && previous && previous->parts_) {
        device_ = previous->device_;
    } else {
        RTCDevice device = rtcNewDevice("threads=0");
        if (!device) throw std::runtime_error("cannot create Embree device");
        rtcSetDeviceErrorFunction(device, embree_error, nullptr);
        device_ = std::shared_ptr<RTCDeviceTy>(device, rtcReleaseDevice);
    }
    if (two_level) {
        parts_ = std::make_unique<BvhParts>(device_.get(), scene, previous ? previous->parts_.get() : nullptr);
        coarse_ = parts_->coarse(device_.get(), scene);
        fine_ = parts_->fine(device_.get(), scene);
        shadow_fur_ = parts_->shadow_fur();
    } else {
        build_flat(scene);
    }
    measure_offsets(scene, settings.ray_offset);
}

BvhReuse SceneAccel::reuse() const { return parts_ ? parts_->reuse() : BvhReuse{}; }

bool SceneAccel::current() const { return !parts_ || parts_->current(); }

void SceneAccel::build_flat(const Scene& scene) {
    RTCDevice device = device_.get();
    const FurLists fur(scene);
    BvhGeometry coarse, fine;
    bool any_fine = false;
    for (size_t i = 0; i < scene.objects.size(); ++i) {
        const Object& o = scene.objects[i];
        coarse.meshes.push_back(o.placed() ? &o.coarse : nullptr);
        coarse.masks.push_back(object_ray_mask(scene, i));
        fine.meshes.push_back(o.placed() ? &o.visible() : nullptr);
        fine.motion.push_back(o.shutter[0].empty() ? nullptr : &o.shutter);  // camera rays see motion blur
        coarse.cutouts.push_back(o.placed() ? CutoutMesh::make(scene.materials, o.coarse) : nullptr);
        fine.cutouts.push_back(!o.placed()    ? nullptr
                               : o.has_fine() ? CutoutMesh::make(scene.materials, o.visible())
                                              : coarse.cutouts.back());
        any_fine |= o.has_fine() || fine.motion.back();
    }
    fine.masks = coarse.masks;
    if (FurLists::any(fur.indirect)) coarse.furs = fur.indirect, coarse.fur_masks = fur.masks;
    coarse_ = std::make_unique<Bvh>(device, coarse);
    // Fur already in the coarse BVH shadows through it; the rest that casts shadows gets its own.
    if (FurLists::any(fur.shadow)) {
        BvhGeometry shadow;
        shadow.meshes.assign(scene.objects.size(), nullptr), shadow.furs = fur.shadow;
        shadow_fur_ = std::make_shared<Bvh>(device, shadow);
    }
    // The camera sees all fur: when that is the shadow BVH's, instance it rather than build it twice.
    if (shadow_fur_ && fur.shadow == fur.visible) {
        fine_ = std::make_unique<Bvh>(device, fine, *shadow_fur_);
    } else if (any_fine || FurLists::any(fur.visible)) {
        fine.furs = fur.visible;
        fine_ = std::make_unique<Bvh>(device, fine);
    }
}

namespace {
/// From each fine vertex (a sample of them), along its normal both ways, the distance to the
/// nearest coarse surface of mesh `id` in `against`, times `stretch`.
void measure_gaps(const TriangleMesh& fine, const TriangleMesh& coarse, const Bvh& against, uint32_t id, float stretch,
                  std::vector<float>& gaps) {
    float reach = 0.05f * length(coarse.bounds().diagonal());
    size_t step = std::max<size_t>(1, fine.positions.size() / 20000);
    for (size_t i = 0; i < fine.positions.size(); i += step) {
        Vec3 p = fine.positions[i];
        Vec3 n = fine.normals.empty() ? Vec3(0, 0, 1) : fine.normals[i];
        if (dot(n, n) == 0) continue;
        Hit a = against.intersect(p, n, 0, reach), b = against.intersect(p, -n, 0, reach);
        float d = std::min(a.object == id ? a.t : INFINITY, b.object == id ? b.t : INFINITY);
        if (std::isfinite(d)) gaps.push_back(d * stretch);
    }
}

const std::vector<BvhParts::Prototype> kNoPrototypes;

/// A placement's largest stretch; a turn's rounding (a few 1e-8) is not one: it would move
/// the gap, and with it every ray's offset, from frame to frame.
float stretch_of(const Transform& t) {
    const float largest = t.largest_scale();
    return std::abs(largest - 1) < 1e-5f ? 1.0f : largest;
}
}  // namespace

void SceneAccel::measure_offsets(const Scene& scene, float ray_offset) {
    // Measure how far the fine surface strays from the coarse one, per object.
    const float diag = scene.size();
    std::vector<float> gaps;
    for (size_t id = 0; id < scene.objects.size(); ++id) {
        const Object& o = scene.objects[id];
        if (!o.has_fine() || o.instance) continue;
        // A rigid mover is measured before its placement, against its own part: the same gap at
        // every frame (measured where it is, float rounding moves it from frame to frame, and
        // with it the offset of every ray in the scene). Scaled by its placement's largest stretch.
        const Bvh* own = parts_ && o.local_fine ? parts_->coarse_part(id) : nullptr;
        const TriangleMesh &fine = own ? *o.local_fine : o.fine, &coarse = own ? *o.local_coarse : o.coarse;
        measure_gaps(fine, coarse, own ? *own : *coarse_, static_cast<uint32_t>(id), own ? stretch_of(o.placement) : 1.0f, gaps);
    }
    // A prototype once, against its own BVH (mesh id 0), stretched as its most stretched placement.
    for (const BvhParts::Prototype& p : parts_ ? parts_->prototypes() : kNoPrototypes) {
        const Object& first = scene.objects[p.instances.front()];
        if (!first.local_fine) continue;
        float stretch = 0;
        for (uint32_t i : p.instances) stretch = std::max(stretch, stretch_of(scene.objects[i].placement));
        measure_gaps(*first.local_fine, *first.local_coarse, *p.coarse.bvh, 0, stretch, gaps);
    }
    // The 99th percentile, not the largest: on a displaced surface a few fine vertices (in
    // folds, at open borders) find the coarse surface only far away, and an offset that large
    // would let rays skip real occluders everywhere.
    if (!gaps.empty()) {
        auto at = gaps.begin() + static_cast<std::ptrdiff_t>(0.99 * static_cast<double>(gaps.size() - 1));
        std::nth_element(gaps.begin(), at, gaps.end());
        gap_ = *at;
    }
    // Default distance: cover the measured gap for rays up to ~75 degrees off the normal.
    ray_offset_ = ray_offset >= 0 ? ray_offset : std::max(1e-4f * diag, 4.0f * gap_);
    min_epsilon_ = 1e-7f * diag;
}

float SceneAccel::self_epsilon(const Vec3& p) const {
    // Well above float rounding of p (2^-24 relative) and of fragment positions averaged over a
    // pixel on curved surfaces, yet independent of how large the scene is.
    const float m = std::max({std::abs(p.x), std::abs(p.y), std::abs(p.z)});
    return std::max(1e-5f * m, min_epsilon_);
}

SceneAccel::~SceneAccel() = default;

float SceneAccel::offset_start(const Vec3& p, const Vec3& d) const {
    const float delta = ray_offset_;
    const Vec3 o = p - d * delta;
    // Coarse hits within [0, 2 delta] come in increasing t; keep the one nearest to p (t = delta).
    float best = -1, tn = 0;
    for (int i = 0; i < 8; ++i) {
        Hit h = coarse_->intersect(o, d, tn, 2 * delta);
        if (!h.valid()) break;
        if (best < 0 || std::abs(h.t - delta) < std::abs(best - delta)) best = h.t;
        if (h.t >= delta) break;  // later hits are farther from p
        tn = std::nextafter(h.t, INFINITY) + 1e-6f * delta;
    }
    // Start just past the chosen crossing; with none, start at p itself.
    return best >= 0 ? best + 1e-4f * delta : delta;
}

Hit SceneAccel::trace(const Vec3& p, const Vec3& d, unsigned mask) const {
    const float delta = ray_offset_;
    // Most rays meet nothing within delta of p: then the offsetting cannot change the hit and
    // one traversal is enough. Only the others (a few %: contacts, interpenetrating or
    // fine-vs-coarse surfaces) pay for the probe.
    Hit first = coarse_->intersect(p, d, self_epsilon(p), INFINITY, 0, mask);
    return !first.valid() || first.t >= delta ? first : probed_trace(p, d, mask);
}

Hit SceneAccel::probed_trace(const Vec3& p, const Vec3& d, unsigned mask) const {
    const float delta = ray_offset_;
    // The probe (offset_start) finds p's own surface whatever sees it; the ray, only what gathers see.
    Hit h = coarse_->intersect(p - d * delta, d, offset_start(p, d), INFINITY, 0, mask);
    if (h.valid()) h.t = std::max(0.0f, h.t - delta);
    return h;
}

void SceneAccel::trace_many(const Vec3& p, std::span<const Vec3> dirs, std::span<Hit> out) const {
    coarse_->intersect_from(p, dirs.data(), dirs.size(), self_epsilon(p), out.data(), kRayIndirect);
    const float delta = ray_offset_;
    // As in trace: only rays meeting something within delta of p pay for the probe.
    for (size_t i = 0; i < dirs.size(); ++i)
        if (out[i].valid() && out[i].t < delta) out[i] = probed_trace(p, dirs[i], kRayIndirect);
}

bool SceneAccel::occluded(const Vec3& p, const Vec3& d, float dist, float hair_start, unsigned mask) const {
    // Fur is on no tessellated surface: traced from p without offsetting, stopping just short
    // of the end point.
    const float fur_end = std::isfinite(dist) ? dist * (1 - 1e-4f) : INFINITY;
    if (hair_start > 0) {
        // From a strand: skip past its own ribbon.
        if (fur_end <= hair_start) return false;
        if (coarse_->occluded(p, d, self_epsilon(p), fur_end, mask)) return true;
        return shadow_fur_ && shadow_fur_->occluded(p, d, hair_start, fur_end);
    }
    if (shadow_fur_ && fur_end > self_epsilon(p) && shadow_fur_->occluded(p, d, self_epsilon(p), fur_end)) return true;
    const float delta = ray_offset_;
    float start = offset_start(p, d);
    // Stop short of the end point so the surface it lies on does not occlude it.
    float end = std::isfinite(dist) ? delta + dist - std::max(delta, 1e-4f * dist) : INFINITY;
    if (end <= start) return false;
    return coarse_->occluded(p - d * delta, d, start, end, mask);
}

}  // namespace bounce
