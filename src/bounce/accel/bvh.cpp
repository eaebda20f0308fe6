#include "bounce/accel/bvh.h"

#include <algorithm>

namespace bounce {

namespace {
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

/// Copies positions into an Embree vertex buffer of `g` (slot `slot`, already allocated).
void fill_vertices(RTCGeometry g, unsigned slot, const std::vector<Vec3>& pos) {
    auto* vb = static_cast<float*>(rtcGetGeometryBufferData(g, RTC_BUFFER_TYPE_VERTEX, slot));
    for (size_t i = 0; i < pos.size(); ++i) vb[3 * i] = pos[i].x, vb[3 * i + 1] = pos[i].y, vb[3 * i + 2] = pos[i].z;
}

template <class T>
T at_or(const std::vector<T>& v, size_t i, T otherwise) {
    return i < v.size() ? v[i] : otherwise;
}
}  // namespace

Bvh::Bvh(RTCDevice device, const BvhGeometry& geometry) : mesh_count_(static_cast<unsigned>(geometry.meshes.size())) {
    begin(device, geometry);
    for (size_t id = 0; id < geometry.furs.size(); ++id) add_fur(device, geometry, id);
    rtcCommitScene(scene_);
}

void Bvh::add_fur(RTCDevice device, const BvhGeometry& geometry, size_t id) {
    const Fur* f = geometry.furs[id];
    if (!f || f->segment_count() == 0) return;
    // Ribbons facing the ray: strands are thinner than a pixel, so their round profile does not
    // show, and flat curves intersect faster. Still fur traces the fur's own buffers; fur that
    // moves in the shutter, copies of its two poses.
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_FLAT_LINEAR_CURVE);
    const FurShutter* moving = at_or<const FurShutter*>(geometry.fur_motion, id, nullptr);
    if (moving && (*moving)[0].size() != f->vertices.size()) moving = nullptr;
    const size_t points = f->vertices.size() / 4;
    if (moving) {
        rtcSetGeometryTimeStepCount(g, 2);
        for (unsigned slot = 0; slot < 2; ++slot) {
            auto* vb =
                static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, slot, RTC_FORMAT_FLOAT4, 4 * sizeof(float), points));
            std::copy((*moving)[slot].begin(), (*moving)[slot].end(), vb);
        }
    } else {
        rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, f->vertices.data(), 0, 4 * sizeof(float), points);
    }
    rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT, f->segment_first.data(), 0, sizeof(uint32_t),
                               f->segment_count());
    rtcSetGeometryMask(g, at_or(geometry.fur_masks, id, kRayAll));
    rtcCommitGeometry(g);
    rtcAttachGeometryByID(scene_, g, mesh_count_ + static_cast<unsigned>(id));
    rtcReleaseGeometry(g);
    empty_ = false;
}

Bvh::Bvh(RTCDevice device, const BvhGeometry& meshes, const Bvh& fur) : mesh_count_(static_cast<unsigned>(meshes.meshes.size())) {
    begin(device, meshes);
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_INSTANCE);
    rtcSetGeometryInstancedScene(g, fur.scene_);
    const float identity[12] = {1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0};
    rtcSetGeometryTransform(g, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, identity);
    rtcSetGeometryMask(g, kRayAll);
    rtcCommitGeometry(g);
    // Past every mesh and fur id: hits report the instanced scene's own geometry ids.
    rtcAttachGeometryByID(scene_, g, 2 * mesh_count_ + 1);
    rtcReleaseGeometry(g);
    empty_ = empty_ && fur.empty();
    rtcCommitScene(scene_);
}

Bvh::Bvh(RTCDevice device, const std::vector<Placed>& placed, unsigned mesh_count) : mesh_count_(mesh_count) {
    scene_ = rtcNewScene(device);
    rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_HIGH);
    rtcSetSceneFlags(scene_, RTC_SCENE_FLAG_ROBUST);
    for (const Placed& p : placed) {
        if (!p.bvh || p.bvh->empty()) continue;
        RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_INSTANCE);
        rtcSetGeometryInstancedScene(g, p.bvh->scene_);
        // Two poses are interpolated linearly, as the vertices of a mesh moving in the shutter are.
        rtcSetGeometryTimeStepCount(g, p.moving ? 2 : 1);
        for (unsigned k = 0; k < (p.moving ? 2u : 1u); ++k) rtcSetGeometryTransform(g, k, RTC_FORMAT_FLOAT3X4_ROW_MAJOR, p.at[k].m.data());
        rtcSetGeometryMask(g, p.mask);
        rtcCommitGeometry(g);
        const unsigned id = rtcAttachGeometry(scene_, g);
        rtcReleaseGeometry(g);
        if (object_of_.size() <= id) object_of_.resize(id + 1, kNoHit);
        object_of_[id] = p.object;
        placed_.push_back(p.bvh);
        empty_ = false;
    }
    rtcCommitScene(scene_);
}

void Bvh::begin(RTCDevice device, const BvhGeometry& geometry) {
    const bool refittable = geometry.refittable;
    scene_ = rtcNewScene(device);
    rtcSetSceneBuildQuality(scene_, refittable ? RTC_BUILD_QUALITY_LOW : RTC_BUILD_QUALITY_HIGH);
    rtcSetSceneFlags(scene_, refittable ? RTC_SCENE_FLAG_ROBUST | RTC_SCENE_FLAG_DYNAMIC : RTC_SCENE_FLAG_ROBUST);
    for (size_t id = 0; id < geometry.meshes.size(); ++id) {
        if (!geometry.meshes[id]) continue;  // an id held for fur only
        const TriangleMesh& m = *geometry.meshes[id];
        RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
        if (refittable) rtcSetGeometryBuildQuality(g, RTC_BUILD_QUALITY_REFIT);
        const ShutterPositions* moving = at_or<const ShutterPositions*>(geometry.motion, id, nullptr);
        if (moving && (*moving)[0].empty()) moving = nullptr;
        if (moving) rtcSetGeometryTimeStepCount(g, 2);
        for (unsigned slot = 0; slot < (moving ? 2u : 1u); ++slot) {
            const std::vector<Vec3>& pos = moving ? (*moving)[slot] : m.positions;
            rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, slot, RTC_FORMAT_FLOAT3, 3 * sizeof(float), pos.size());
            fill_vertices(g, slot, pos);
        }
        auto* ib = static_cast<uint32_t*>(
            rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(uint32_t), m.triangle_count()));
        std::copy(m.indices.begin(), m.indices.end(), ib);
        if (id < geometry.masks.size()) rtcSetGeometryMask(g, geometry.masks[id]);
        if (const auto& cut = at_or<std::shared_ptr<const CutoutMesh>>(geometry.cutouts, id, nullptr)) {
            cut->attach(g);
            cutouts_.push_back(cut);
        }
        rtcCommitGeometry(g);
        rtcAttachGeometryByID(scene_, g, static_cast<unsigned>(id));
        rtcReleaseGeometry(g);
        empty_ = false;
    }
}

void Bvh::refit(unsigned id, const TriangleMesh& mesh, const ShutterPositions* motion) {
    RTCGeometry g = rtcGetGeometry(scene_, id);
    const bool moving = motion && !(*motion)[0].empty();
    for (unsigned slot = 0; slot < (moving ? 2u : 1u); ++slot) {
        fill_vertices(g, slot, moving ? (*motion)[slot] : mesh.positions);
        rtcUpdateGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, slot);
    }
    rtcCommitGeometry(g);
}

void Bvh::commit() {
    rtcCommitScene(scene_);
    ++refits_;
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
    return make_hit(rh.hit.geomID, rh.hit.instID[0], rh.hit.primID, rh.ray.tfar, rh.hit.u, rh.hit.v);
}

Hit Bvh::make_hit(unsigned geom, unsigned instance, unsigned prim, float t, float u, float v) const {
    Hit h;
    h.t = t;
    const uint32_t placed = instance < object_of_.size() ? object_of_[instance] : kNoHit;
    h.hair = placed == kNoHit && geom >= mesh_count_;
    h.object = placed != kNoHit ? placed : h.hair ? geom - mesh_count_ : geom;
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
            out[base + i] = rh.hit.geomID[i] == RTC_INVALID_GEOMETRY_ID ? Hit{}
                                                                        : make_hit(rh.hit.geomID[i], rh.hit.instID[0][i], rh.hit.primID[i],
                                                                                   rh.ray.tfar[i], rh.hit.u[i], rh.hit.v[i]);
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

}  // namespace bounce
