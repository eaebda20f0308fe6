#include "bounce/accel/cutouts.h"

#include <OpenImageIO/hash.h>

#include <algorithm>
#include <bit>

#include "bounce/accel/bvh.h"
#include "bounce/core/random.h"
#include "bounce/scene/opacity.h"

namespace bounce {

namespace {

bool has_cutout(const std::vector<Material>& materials, const TriangleMesh& mesh) {
    return std::any_of(mesh.face_materials.begin(), mesh.face_materials.end(),
                       [&](uint32_t m) { return m < materials.size() && materials[m].is_cutout(); });
}

}  // namespace

std::shared_ptr<const CutoutMesh> CutoutMesh::make(const std::vector<Material>& materials, const TriangleMesh& mesh) {
    if (!has_cutout(materials, mesh)) return nullptr;
    auto c = std::make_shared<CutoutMesh>();
    c->cuts_.resize(materials.size());
    for (size_t i = 0; i < materials.size(); ++i) {
        const Material& m = materials[i];
        c->cuts_[i] = {m.alpha_mode, m.opacity, m.alpha_cutoff, m.opacity_map};
    }
    c->uvs_ = mesh.uvs;
    c->indices_ = mesh.indices;
    c->face_materials_ = mesh.face_materials;
    return c;
}

uint64_t CutoutMesh::key(const std::vector<Material>& materials, const TriangleMesh& mesh) {
    if (!has_cutout(materials, mesh)) return 0;
    uint64_t h = OIIO::xxhash::XXH64(mesh.uvs.data(), mesh.uvs.size() * sizeof(Vec2), 0x61c88647);
    h = OIIO::xxhash::XXH64(mesh.face_materials.data(), mesh.face_materials.size() * sizeof(uint32_t), h);
    for (const Material& m : materials) h = hash_combine(h, cutout_identity(m));
    return h | 1;
}

float CutoutMesh::opacity(uint32_t prim, float u, float v) const {
    const Cut& c = cuts_[face_materials_[prim]];
    if (c.mode == AlphaMode::Opaque) return 1;
    if (!c.map || uvs_.empty()) return c.opacity;
    const uint32_t* t = &indices_[3 * static_cast<size_t>(prim)];
    const Vec2 &a = uvs_[t[0]], &b = uvs_[t[1]], &d = uvs_[t[2]];
    const float w = 1 - u - v;
    return c.opacity * c.map->at({w * a.x + u * b.x + v * d.x, w * a.y + u * b.y + v * d.y});
}

bool CutoutMesh::stops(uint32_t prim, float u, float v, bool camera, uint64_t ray_hash) const {
    const Cut& c = cuts_[face_materials_[prim]];
    if (c.mode == AlphaMode::Opaque) return true;
    const float a = opacity(prim, u, v);
    if (c.mode == AlphaMode::Mask) return a >= c.cutoff;
    return camera ? a > 0 : to_unit_float(ray_hash) < a;
}

namespace {

/// The same ray meets the same decision at the same triangle, whichever traversal (or process)
/// asks: the hash of its origin, direction and the triangle.
uint64_t ray_hash(const RTCFilterFunctionNArguments* args, unsigned i, unsigned prim) {
    const unsigned n = args->N;
    RTCRayN* r = args->ray;
    uint64_t h = 0x6a09e667f3bcc909ULL;
    for (float f : {RTCRayN_org_x(r, n, i), RTCRayN_org_y(r, n, i), RTCRayN_org_z(r, n, i), RTCRayN_dir_x(r, n, i), RTCRayN_dir_y(r, n, i),
                    RTCRayN_dir_z(r, n, i)})
        h = hash_combine(h, std::bit_cast<uint32_t>(f));
    return hash_combine(h, prim);
}

void cutout_filter(const RTCFilterFunctionNArguments* args) {
    const auto* mesh = static_cast<const CutoutMesh*>(args->geometryUserPtr);
    const unsigned n = args->N;
    for (unsigned i = 0; i < n; ++i) {
        if (args->valid[i] != -1) continue;
        const unsigned prim = RTCHitN_primID(args->hit, n, i);
        const bool camera = RTCRayN_mask(args->ray, n, i) == kRayCamera;
        // Only a blended surface met by a secondary ray draws a number.
        const uint64_t hash = !camera && mesh->mode(prim) == AlphaMode::Blend ? ray_hash(args, i, prim) : 0;
        if (!mesh->stops(prim, RTCHitN_u(args->hit, n, i), RTCHitN_v(args->hit, n, i), camera, hash)) args->valid[i] = 0;
    }
}

}  // namespace

void CutoutMesh::attach(RTCGeometry g) const {
    rtcSetGeometryUserData(g, const_cast<CutoutMesh*>(this));
    rtcSetGeometryIntersectFilterFunction(g, cutout_filter);
    rtcSetGeometryOccludedFilterFunction(g, cutout_filter);
}

}  // namespace bounce
