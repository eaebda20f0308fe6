// Radiosity textures across the frames of a shot: kept texel for texel, re-baked only where the
// direct light may have changed (docs/animation.md).
#include <algorithm>
#include <cstring>
#include <initializer_list>
#include <limits>
#include <stdexcept>

#include "bounce/core/parallel.h"
#include "bounce/radiosity/radiosity.h"

namespace bounce {

namespace {

bool boxes_overlap(const Bounds& a, const Bounds& b) {
    return !a.empty() && !b.empty() && a.lo.x <= b.hi.x && b.lo.x <= a.hi.x && a.lo.y <= b.hi.y && b.lo.y <= a.hi.y && a.lo.z <= b.hi.z &&
           b.lo.z <= a.hi.z;
}

/// Conservatively, can `box` stand between `points` (a triangle side facing `n`, or a box's
/// corners facing every way: n = 0) and `light`, i.e. shadow them or stop shadowing them? Their
/// box and the light's extent (a point, a quad, or the points pushed far towards a distant
/// light or the sky) must overlap it.
bool may_shadow(const Light& light, std::initializer_list<Vec3> points, const Vec3& n, const Bounds& box, float far) {
    Bounds hull;
    for (const Vec3& p : points) hull.extend(p);
    switch (light.type) {
        case LightType::Point:
        case LightType::Spot:
            hull.extend(light.position);
            break;
        case LightType::Quad:
            for (const Vec3& p :
                 {light.corner, light.corner + light.edge_u, light.corner + light.edge_v, light.corner + light.edge_u + light.edge_v})
                hull.extend(p);
            break;
        case LightType::Distant:
            for (const Vec3& p : points) hull.extend(p - light.direction * far);
            break;
        case LightType::Sky:
        case LightType::Mesh:
            // Anything above the side's plane may hide part of the sky (or an emissive mesh): the
            // hemisphere reaches along every axis but the one straight behind it (a floor's sky is
            // hidden by a wall beside it, not only by what is overhead).
            for (const Vec3& p : points)
                for (const Vec3& d :
                     {Vec3{far, 0, 0}, Vec3{-far, 0, 0}, Vec3{0, far, 0}, Vec3{0, -far, 0}, Vec3{0, 0, far}, Vec3{0, 0, -far}})
                    if (dot(d, n) > -0.9999f * far) hull.extend(p + d);
            break;
    }
    return boxes_overlap(hull, box);
}

/// Does anything this frame change the direct light at `obj`'s surface (its placement, a
/// material of its, any light, or a mover that may come between it and a light)?
bool light_may_change(const Scene& scene, const SceneChanges& changes, size_t id, float far) {
    const Object& obj = scene.objects[id];
    if (changes.lights || changes.objects[id].kind != ObjectMotion::Kind::Static) return true;
    const TriangleMesh& m = obj.coarse_mesh();
    if (obj.material_override >= 0
            ? changes.materials[static_cast<size_t>(obj.material_override)]
            : std::any_of(m.face_materials.begin(), m.face_materials.end(), [&](uint32_t f) { return changes.materials[f]; }))
        return true;
    for (size_t o = 0; o < changes.objects.size(); ++o)
        if (o != id && changes.objects[o].kind != ObjectMotion::Kind::Static)
            for (const Light& l : scene.lights)
                if (may_shadow(l, {obj.coarse_bounds().lo, obj.coarse_bounds().hi}, Vec3{0, 0, 0}, changes.objects[o].swept, far))
                    return true;
    return false;
}

}  // namespace

float RadiosityTextures::brightest() const {
    // A small instance lit at the hit holds no values to bound its light by: anything.
    if (std::any_of(maps_.begin(), maps_.end(), [](const RadiosityMap& m) { return m.lit_at_hit; }))
        return std::numeric_limits<float>::max();
    float top = 0;
    for (size_t id = 0; id < maps_.size(); ++id)
        for (size_t t = 0; t < maps_[id].level.size(); ++t)
            for (int side = 0; side < 2; ++side) {
                if (state_[id].load(2 * t + static_cast<size_t>(side), std::memory_order_relaxed) != 2) continue;
                const RadiosityMap& m = maps_[id];
                const Color* v = (side == 0 ? m.front : m.back).run(static_cast<uint32_t>(t), m.offset[t]);
                const uint32_t n = lattice_count(m.level[t]);
                for (uint32_t k = 0; v && k < n; ++k) top = std::max(top, luminance(v[k]));
            }
    return top;
}

RadiosityTextures RadiosityTextures::carry(const RadiosityTextures& previous, const Scene& scene, const Materials& materials,
                                           const DirectLighting& lighting, const RadiositySettings& settings, const SceneChanges& changes,
                                           std::vector<LightChange>& changed, Stats& stats) {
    RadiosityTextures rt;
    rt.texel_size_ = previous.texel_size_;
    rt.fingerprint_ = fingerprint(scene, settings, lighting.settings().light_samples);
    rt.sources_ = std::make_unique<Sources>(*previous.sources_);
    rt.sources_->scene = &scene, rt.sources_->materials = &materials, rt.sources_->lighting = &lighting;
    if (rt.has_parts()) rt.sources_->scales = light_scales(scene);  // the plan carries parts only between alike lights
    rt.maps_ = previous.maps_;
    rt.names_ = previous.names_;
    const float far = 2 * std::max(1e-6f, length(scene.bounds().diagonal()));
    // Which baked sides to bake again, then bake them (in parallel) and compare.
    std::vector<std::pair<uint32_t, uint32_t>> redo;  // (object, 2 * triangle + side)
    for (size_t id = 0; id < previous.state_.size(); ++id) {
        const size_t n = previous.maps_[id].sides_baked_apart();
        rt.state_.emplace_back(n);
        const Object& obj = scene.objects[id];
        const bool moved = changes.objects[id].kind != ObjectMotion::Kind::Static;
        if (changes.objects[id].kind == ObjectMotion::Kind::Deforming) {
            // Its triangles changed size: lay it out as this frame alone would, every side lazy.
            rt.maps_[id] = rt.laid_out(scene, id, settings);
            rt.state_.back() = SideStates(rt.maps_[id].sides_baked_apart());
            continue;
        }
        if (rt.maps_[id].lit_at_hit) {  // never baked: every hit on it changes with its light
            if (light_may_change(scene, changes, id, far))
                changed.push_back(
                    {obj.coarse_bounds(), std::numeric_limits<float>::max(), static_cast<uint32_t>(id), LightChange::kEveryTriangle});
            continue;
        }
        for (size_t s = 0; s < n; ++s) {
            const uint8_t was = previous.state_[id].load(s, std::memory_order_relaxed) == 2 ? 2 : 0;
            rt.state_.back().store(s, was, std::memory_order_relaxed);
            if (was != 2) continue;
            const size_t t = s / 2;
            bool again = changes.lights || moved || changes.materials[obj.material_of(static_cast<uint32_t>(t))];
            if (!again && changes.moving()) {
                const auto [a, b, c] = triangle_vertices(obj.coarse_mesh(), obj.to_world(), static_cast<uint32_t>(t));
                const Vec3 ng = normalize(cross(b - a, c - a)) * (s % 2 == 0 ? 1.0f : -1.0f);
                for (size_t o = 0; o < changes.objects.size() && !again; ++o)
                    if (o != id && changes.objects[o].kind != ObjectMotion::Kind::Static)
                        for (const Light& l : scene.lights) again = again || may_shadow(l, {a, b, c}, ng, changes.objects[o].swept, far);
            }
            if (again) redo.emplace_back(static_cast<uint32_t>(id), static_cast<uint32_t>(s));
        }
    }
    for (auto [id, s] : redo) rt.state_[id].store(s, 0, std::memory_order_relaxed);
    std::vector<LightChange> found(redo.size());
    parallel_ranges(size_t{0}, redo.size(), size_t{16}, [&](size_t lo, size_t hi) {
        Counters& counters = stats.local();
        for (size_t i = lo; i < hi; ++i) {
            const auto [id, s] = redo[i];
            const uint32_t t = s / 2;
            const bool front = s % 2 == 0;
            rt.ensure_baked(id, t, front, counters);
            const RadiosityMap &now = rt.maps_[id], &was = previous.maps_[id];
            const Color *vn = (front ? now.front : now.back).run(t, now.offset[t]),
                        *vw = (front ? was.front : was.back).run(t, was.offset[t]);
            const uint32_t count = lattice_count(now.level[t]);
            float delta = 0;
            for (uint32_t k = 0; vn && vw && k < count; ++k)
                delta = std::max({delta, std::abs(vn[k].x - vw[k].x), std::abs(vn[k].y - vw[k].y), std::abs(vn[k].z - vw[k].z)});
            if (delta <= 0) continue;
            const Object& o = scene.objects[id];
            Bounds b;
            for (const Vec3& v : triangle_vertices(o.coarse_mesh(), o.to_world(), t)) b.extend(v);
            found[i] = {b, delta, id, t};
        }
    });
    for (const LightChange& c : found)
        if (c.delta > 0) changed.push_back(c);
    stats.set("radiosity_sides_rebaked", static_cast<double>(redo.size()));
    stats.set("radiosity_sides_changed", static_cast<double>(changed.size()));
    return rt;
}

std::string RadiosityTextures::baked_bytes() const {
    std::string out;
    const auto put = [&out](const void* p, size_t n) { out.append(static_cast<const char*>(p), n); };
    for (uint32_t id = 0; id < state_.size(); ++id) {
        const RadiosityMap& m = maps_[id];
        for (uint32_t s = 0; s < 2 * m.level.size(); ++s) {
            if (state_[id].load(s, std::memory_order_acquire) != 2) continue;
            const uint32_t t = s / 2, count = lattice_count(m.level[t]);
            const uint32_t head[3] = {id, s, count};
            put(head, sizeof(head));
            put((s % 2 == 0 ? m.front : m.back).run(t, m.offset[t]), count * sizeof(Color));
        }
    }
    return out;
}

void RadiosityTextures::take_baked(const std::string& bytes) {
    for (size_t at = 0; at + 3 * sizeof(uint32_t) <= bytes.size();) {
        uint32_t head[3];
        std::memcpy(head, bytes.data() + at, sizeof(head));
        at += sizeof(head);
        const auto [id, s, count] = head;
        RadiosityMap& m = maps_.at(id);
        const uint32_t t = s / 2;
        // (Bytes from this build's ranks; a side that does not fit would write past its page.)
        if (s >= state_[id].size() || count != lattice_count(m.level[t]) || at + size_t{count} * sizeof(Color) > bytes.size())
            throw std::runtime_error("radiosity exchange: a side that does not exist");
        if (state_[id].load(s, std::memory_order_acquire) != 2) {
            std::memcpy(static_cast<void*>((s % 2 == 0 ? m.front : m.back).writable_run(t, m.offset.at(t))), bytes.data() + at,
                        count * sizeof(Color));
            state_[id].store(s, 2, std::memory_order_release);
        }
        at += count * sizeof(Color);
    }
}

}  // namespace bounce
