#include "bounce/accel/accel.h"

#include <fmt/format.h>

#include <new>

#include "bounce/core/memory.h"

#include <algorithm>
#include <stdexcept>

namespace bounce {

namespace {
void embree_error(void*, RTCError code, const char* str) {
    if (code == RTC_ERROR_NONE) return;
    if (code == RTC_ERROR_OUT_OF_MEMORY) throw std::bad_alloc();
    throw std::runtime_error(fmt::format("Embree error {}: {}", static_cast<int>(code), str ? str : ""));
}

RTCRayHit make_ray(const Vec3& o, const Vec3& d, float tnear, float tfar, unsigned mask) {
    RTCRayHit rh{};
    rh.ray.org_x = o.x, rh.ray.org_y = o.y, rh.ray.org_z = o.z;
    rh.ray.dir_x = d.x, rh.ray.dir_y = d.y, rh.ray.dir_z = d.z;
    rh.ray.tnear = tnear;
    rh.ray.tfar = tfar;
    rh.ray.mask = mask;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    return rh;
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

Bvh::Bvh(RTCDevice device, const std::vector<const TriangleMesh*>& meshes, const std::vector<const Fur*>& furs,
         const std::vector<const std::array<std::vector<Vec3>, 2>*>& motion, const std::vector<unsigned>& masks,
         const std::vector<unsigned>& fur_masks)
    : mesh_count_(static_cast<unsigned>(meshes.size())) {
    begin(device, meshes, motion, masks);
    for (size_t id = 0; id < furs.size(); ++id) {
        const Fur* f = furs[id];
        if (!f || f->segment_count() == 0) continue;
        // Ribbons facing the ray: strands are thinner than a pixel, so their round profile
        // does not show, and flat curves intersect faster. The buffers are the fur's own.
        RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_FLAT_LINEAR_CURVE);
        rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, f->vertices.data(), 0,
                                   4 * sizeof(float), f->vertices.size() / 4);
        rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT, f->segment_first.data(), 0,
                                   sizeof(uint32_t), f->segment_count());
        rtcSetGeometryMask(g, fur_masks.empty() ? kRayAll : fur_masks[id]);
        rtcCommitGeometry(g);
        rtcAttachGeometryByID(scene_, g, mesh_count_ + static_cast<unsigned>(id));
        rtcReleaseGeometry(g);
    }
    rtcCommitScene(scene_);
}

Bvh::Bvh(RTCDevice device, const std::vector<const TriangleMesh*>& meshes, const Bvh& fur,
         const std::vector<const std::array<std::vector<Vec3>, 2>*>& motion, const std::vector<unsigned>& masks)
    : mesh_count_(static_cast<unsigned>(meshes.size())) {
    begin(device, meshes, motion, masks);
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_INSTANCE);
    rtcSetGeometryInstancedScene(g, fur.scene_);
    const float identity[12] = {1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0};
    rtcSetGeometryTransform(g, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, identity);
    rtcSetGeometryMask(g, kRayAll);
    rtcCommitGeometry(g);
    // Past every mesh and fur id: hits report the instanced scene's own geometry ids.
    rtcAttachGeometryByID(scene_, g, 2 * mesh_count_ + 1);
    rtcReleaseGeometry(g);
    rtcCommitScene(scene_);
}

void Bvh::begin(RTCDevice device, const std::vector<const TriangleMesh*>& meshes,
                const std::vector<const std::array<std::vector<Vec3>, 2>*>& motion, const std::vector<unsigned>& masks) {
    scene_ = rtcNewScene(device);
    rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_HIGH);
    rtcSetSceneFlags(scene_, RTC_SCENE_FLAG_ROBUST);
    for (size_t id = 0; id < meshes.size(); ++id) {
        if (!meshes[id]) continue;  // an id held for fur only
        const TriangleMesh& m = *meshes[id];
        RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
        const auto* moving = id < motion.size() && motion[id] && !(*motion[id])[0].empty() ? motion[id] : nullptr;
        if (moving) rtcSetGeometryTimeStepCount(g, 2);
        for (unsigned slot = 0; slot < (moving ? 2u : 1u); ++slot) {
            const std::vector<Vec3>& pos = moving ? (*moving)[slot] : m.positions;
            auto* vb = static_cast<float*>(
                rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, slot, RTC_FORMAT_FLOAT3, 3 * sizeof(float), pos.size()));
            for (size_t i = 0; i < pos.size(); ++i) vb[3 * i] = pos[i].x, vb[3 * i + 1] = pos[i].y, vb[3 * i + 2] = pos[i].z;
        }
        auto* ib = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(
            g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(uint32_t), m.triangle_count()));
        std::copy(m.indices.begin(), m.indices.end(), ib);
        if (id < masks.size()) rtcSetGeometryMask(g, masks[id]);
        rtcCommitGeometry(g);
        rtcAttachGeometryByID(scene_, g, static_cast<unsigned>(id));
        rtcReleaseGeometry(g);
    }
}

Bvh::~Bvh() {
    if (scene_) rtcReleaseScene(scene_);
}

Hit Bvh::intersect(const Vec3& o, const Vec3& d, float tnear, float tfar, float time, unsigned mask) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRayHit rh = make_ray(o, d, tnear, tfar, mask);
    rh.ray.time = time;
    rtcIntersect1(scene_, &ctx, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return Hit{};
    return make_hit(rh.hit.geomID, rh.hit.primID, rh.ray.tfar, rh.hit.u, rh.hit.v);
}

Hit Bvh::make_hit(unsigned geom, unsigned prim, float t, float u, float v) const {
    Hit h;
    h.t = t;
    h.hair = geom >= mesh_count_;
    h.object = h.hair ? geom - mesh_count_ : geom;
    h.prim = prim;
    h.u = u;
    h.v = v;
    return h;
}

void Bvh::intersect_from(const Vec3& o, const Vec3* d, size_t count, float tnear, Hit* out, unsigned mask) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    constexpr size_t K = 16;
    for (size_t base = 0; base < count; base += K) {
        const size_t n = std::min(K, count - base);
        alignas(64) RTCRayHit16 rh;
        alignas(64) int valid[K];
        for (size_t i = 0; i < K; ++i) {
            const bool on = i < n;
            valid[i] = on ? -1 : 0;
            const Vec3& di = d[base + (on ? i : 0)];
            rh.ray.org_x[i] = o.x, rh.ray.org_y[i] = o.y, rh.ray.org_z[i] = o.z;
            rh.ray.dir_x[i] = di.x, rh.ray.dir_y[i] = di.y, rh.ray.dir_z[i] = di.z;
            rh.ray.tnear[i] = tnear;
            rh.ray.tfar[i] = INFINITY;
            rh.ray.time[i] = 0;
            rh.ray.mask[i] = mask;
            rh.ray.id[i] = static_cast<unsigned>(i);
            rh.ray.flags[i] = 0;
            rh.hit.geomID[i] = RTC_INVALID_GEOMETRY_ID;
            rh.hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;
        }
        rtcIntersect16(valid, scene_, &ctx, &rh);
        for (size_t i = 0; i < n; ++i) {
            out[base + i] = rh.hit.geomID[i] == RTC_INVALID_GEOMETRY_ID
                                ? Hit{}
                                : make_hit(rh.hit.geomID[i], rh.hit.primID[i], rh.ray.tfar[i], rh.hit.u[i], rh.hit.v[i]);
        }
    }
}

bool Bvh::occluded(const Vec3& o, const Vec3& d, float tnear, float tfar, unsigned mask) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRay r = make_ray(o, d, tnear, tfar, mask).ray;
    rtcOccluded1(scene_, &ctx, &r);
    return r.tfar < 0;  // Embree sets tfar to -inf on a hit
}

SceneAccel::SceneAccel(const Scene& scene) {
    // Refused before Embree allocates: about 100 bytes per triangle and 80 per fur segment
    // and BVH (measured on the ogre and the furry ball), the fine tessellation twice over.
    double triangles = 0, segments = 0;
    for (const auto& o : scene.objects) {
        triangles += static_cast<double>(o.coarse.triangle_count() + (o.has_fine() ? o.fine.triangle_count() : 0));
        if (o.fur) segments += 2.0 * static_cast<double>(o.fur->segment_count());
    }
    check_memory(100 * triangles + 80 * segments, scene.path, "objects",
                 fmt::format("ray tracing {:.3g} triangles and {:.3g} fur segments", triangles, segments / 2));
    device_ = rtcNewDevice("threads=0");
    if (!device_) throw std::runtime_error("cannot create Embree device");
    rtcSetDeviceErrorFunction(device_, embree_error, nullptr);
    std::vector<const TriangleMesh*> coarse, fine;
    // Fur (FurParams::visible_to): in the fine BVH when the camera sees it; in the coarse one,
    // with its mask, when gathers or mirrors do; else in a shadow BVH of its own when it casts shadows.
    std::vector<const Fur*> visible_fur, indirect_fur, shadow_fur;
    std::vector<const std::array<std::vector<Vec3>, 2>*> motion;  // camera rays see motion blur
    std::vector<unsigned> masks, fur_masks;  // which rays see each object, and its fur
    bool any_fine = false, any_fur = false, any_indirect = false, any_shadow = false;
    for (const auto& o : scene.objects) {
        coarse.push_back(&o.coarse);
        masks.push_back(object_ray_mask(scene, masks.size()));
        fine.push_back(&o.visible());
        motion.push_back(o.shutter[0].empty() ? nullptr : &o.shutter);
        any_fine |= o.has_fine() || motion.back();
        const Fur* f = o.fur && o.fur->segment_count() ? o.fur.get() : nullptr;
        const RayVisibility to = f ? f->params.visible_to : RayVisibility{};
        fur_masks.push_back(fur_ray_mask(scene, fur_masks.size()));
        visible_fur.push_back(f && to.camera ? f : nullptr);
        indirect_fur.push_back(f && (to.indirect || to.reflections) ? f : nullptr);
        shadow_fur.push_back(f && to.shadows && !indirect_fur.back() ? f : nullptr);
        any_fur |= visible_fur.back() != nullptr;
        any_indirect |= indirect_fur.back() != nullptr;
        any_shadow |= shadow_fur.back() != nullptr;
    }
    coarse_ = std::make_unique<Bvh>(device_, coarse, any_indirect ? indirect_fur : std::vector<const Fur*>{},
                                    std::vector<const std::array<std::vector<Vec3>, 2>*>{}, masks, fur_masks);
    // Fur already in the coarse BVH shadows through it; the rest that casts shadows gets its own.
    if (any_shadow) shadow_fur_ = std::make_unique<Bvh>(device_, std::vector<const TriangleMesh*>(scene.objects.size(), nullptr), shadow_fur);
    // The camera sees all fur: when that is the shadow BVH's, instance it rather than build it twice.
    if (any_shadow && shadow_fur == visible_fur) fine_ = std::make_unique<Bvh>(device_, fine, *shadow_fur_, motion, masks);
    else if (any_fine || any_fur) fine_ = std::make_unique<Bvh>(device_, fine, visible_fur, motion, masks);

    // Measure how far the fine surface strays from the coarse one: from each fine vertex,
    // along its normal both ways, to the nearest coarse surface of the same object.
    const float diag = scene.size();
    std::vector<float> gaps;
    for (size_t id = 0; id < scene.objects.size(); ++id) {
        const Object& o = scene.objects[id];
        if (!o.has_fine()) continue;
        float reach = 0.05f * length(o.coarse.bounds().diagonal());
        size_t step = std::max<size_t>(1, o.fine.positions.size() / 20000);
        for (size_t i = 0; i < o.fine.positions.size(); i += step) {
            Vec3 p = o.fine.positions[i];
            Vec3 n = o.fine.normals.empty() ? Vec3(0, 0, 1) : o.fine.normals[i];
            if (dot(n, n) == 0) continue;
            Hit a = coarse_->intersect(p, n, 0, reach), b = coarse_->intersect(p, -n, 0, reach);
            float d = std::min(a.object == id ? a.t : INFINITY, b.object == id ? b.t : INFINITY);
            if (std::isfinite(d)) gaps.push_back(d);
        }
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
    ray_offset_ = scene.render.lighting.ray_offset >= 0 ? scene.render.lighting.ray_offset
                                               : std::max(1e-4f * diag, 4.0f * gap_);
    min_epsilon_ = 1e-7f * diag;
}

float SceneAccel::self_epsilon(const Vec3& p) const {
    // Well above float rounding of p (2^-24 relative) and of fragment positions averaged over a
    // pixel on curved surfaces, yet independent of how large the scene is.
    const float m = std::max({std::abs(p.x), std::abs(p.y), std::abs(p.z)});
    return std::max(1e-5f * m, min_epsilon_);
}

SceneAccel::~SceneAccel() {
    shadow_fur_.reset();
    fine_.reset();
    coarse_.reset();
    if (device_) rtcReleaseDevice(device_);
}

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
