#include "bounce/lighting/lighting.h"

#include <algorithm>

namespace bounce {

namespace {

/// What a spot sends along unit `d` (from the light) besides its cone: 0 beyond its barn doors,
/// else its slide's colour (1 without one), the slide covering the outer cone.
Color spot_filter(const Light& l, const Vec3& d) {
    // Most spots have neither: no frame to build on every shadow sample.
    if (!l.texture && std::all_of(l.barn_doors.begin(), l.barn_doors.end(), [](float a) { return a >= 90; })) return Color(1);
    const Vec3 fwd = l.direction;
    const Vec3 right = normalize(std::abs(fwd.y) > 0.999f ? cross(fwd, Vec3(1, 0, 0)) : cross(fwd, Vec3(0, 1, 0)));
    const Vec3 up = cross(right, fwd);
    const float along = dot(d, fwd);
    if (along <= 0) return Color(0);
    const float x = dot(d, right) / along, y = dot(d, up) / along;  // tangents of the angles off the axis
    const auto beyond = [](float t, float door_deg) { return door_deg < 90 && t > std::tan(door_deg * kPi / 180); };
    if (beyond(-x, l.barn_doors[0]) || beyond(x, l.barn_doors[1]) || beyond(y, l.barn_doors[2]) || beyond(-y, l.barn_doors[3]))
        return Color(0);
    if (!l.texture) return Color(1);
    const float half = std::tan(std::min(l.cone_angle + l.cone_falloff, 89.0f) * kPi / 180);
    const float u = 0.5f + x / (2 * half), v = 0.5f - y / (2 * half);
    return u < 0 || u > 1 || v < 0 || v > 1 ? Color(0) : l.texture->at_uv(u, v);
}

}  // namespace

DirectLighting::DirectLighting(const Scene& scene, const SceneAccel& accel, const LightingSettings& settings)
    : scene_(scene),
      accel_(accel),
      settings_(settings),
      emitters_(scene.lights.size()),
      scratch_(std::make_unique<PerThread<ScratchBuffer>>()) {
    for (size_t i = 0; i < scene.lights.size(); ++i) {
        const Light& l = scene.lights[i];
        if (l.type != LightType::Mesh) continue;
        Emitter& e = emitters_[i];
        e.object = l.object;
        const TriangleMesh& m = scene.objects[l.object].coarse;
        for (uint32_t t = 0; t < m.triangle_count(); ++t) {
            if (!scene.materials[m.face_materials[t]].is_emissive()) continue;
            const float area = m.triangle_area(t);
            if (area <= 0) continue;
            e.area += area;
            e.prims.push_back(t);
            e.cdf.push_back(e.area);
        }
    }
}

Color DirectLighting::irradiance(const Vec3& p, const Vec3& n, uint32_t object, const RandomStream& rng, int samples, Counters& counters,
                                 bool include_sky, const LightSampleFn* each, float hair_start) const {
    Color e(0);
    const auto pick = static_cast<size_t>(std::max(0, settings_.light_pick));
    const auto takes = [&](const Light& l) { return (include_sky || l.type != LightType::Sky) && l.lights(object); };
    const auto pickable = [&](const Light& l) {
        return pick > 0 && (l.type == LightType::Point || l.type == LightType::Spot || l.type == LightType::Quad);
    };
    size_t pickables = 0;
    for (size_t i = 0; i < scene_.lights.size(); ++i) {
        const Light& l = scene_.lights[i];
        if (!takes(l)) continue;
        if (pickable(l))
            ++pickables;
        else
            e += sample_light(i, p, n, rng, samples, counters, each, hair_start);
    }
    if (pickables <= pick) {  // few enough: every one, as always (in the order a pool would hold them)
        for (size_t i = 0; i < scene_.lights.size() && pickables > 0; ++i)
            if (takes(scene_.lights[i]) && pickable(scene_.lights[i])) e += sample_light(i, p, n, rng, samples, counters, each, hair_start);
        return e;
    }
    // Many lights: the pool to pick from, in this thread's scratch.
    ScratchBuffer& scratch = scratch_->local();
    const auto scope = scratch.scope();
    const std::span<size_t> pool = scratch.take<size_t>(pickables);
    for (size_t i = 0, k = 0; i < scene_.lights.size(); ++i)
        if (takes(scene_.lights[i]) && pickable(scene_.lights[i])) pool[k++] = i;
    return e + picked_irradiance(pool, p, n, rng, samples, counters, each, hair_start, scratch);
}

namespace {

/// What light `l` may give a point at p facing n, unshadowed (the pick's importance; 0 only
/// where it gives nothing).
float unshadowed_estimate(const Light& l, const Vec3& p, const Vec3& n) {
    const float power = std::max(0.0f, luminance(l.color));
    Vec3 centre = l.position;
    float area = 1;
    if (l.type == LightType::Quad) centre = l.corner + (l.edge_u + l.edge_v) * 0.5f, area = length(cross(l.edge_u, l.edge_v));
    const Vec3 to = centre - p;
    const float r2 = std::max(dot(to, to), 1e-12f);
    // A quad's centre may lie below the horizon while a corner does not: its share is kept by
    // the even tenth of the pick, so only a point or spot light behind p gets nothing here.
    const float cos_x = dot(n, to) / std::sqrt(r2);
    const float facing = l.type == LightType::Quad ? std::max(cos_x, 0.05f) : std::max(cos_x, 0.0f);
    return power * area * facing / r2;
}

}  // namespace

Color DirectLighting::picked_irradiance(std::span<const size_t> pool, const Vec3& p, const Vec3& n, const RandomStream& rng, int samples,
                                        Counters& counters, const LightSampleFn* each, float hair_start, ScratchBuffer& scratch) const {
    const std::span<double> cdf = scratch.take<double>(pool.size());
    double total = 0;
    for (size_t k = 0; k < pool.size(); ++k) cdf[k] = total += unshadowed_estimate(scene_.lights[pool[k]], p, n);
    const double even = 1.0 / static_cast<double>(pool.size());
    const auto chance = [&](size_t k) {
        const double own = total > 0 ? (cdf[k] - (k ? cdf[k - 1] : 0)) / total : even;
        return 0.9 * own + 0.1 * even;
    };
    const int picks = settings_.light_pick;
    Color e(0);
    for (int j = 0; j < picks; ++j) {
        // A tenth of the picks' chance is spread evenly, the rest follows the estimates.
        const double u = rng.get(static_cast<uint64_t>(j), kDimLightPick);
        const auto count = static_cast<double>(pool.size());
        size_t k = 0;
        if (total <= 0)
            k = static_cast<size_t>(u * count);  // nothing to go by: even
        else if (u < 0.1)
            k = static_cast<size_t>(u / 0.1 * count);  // the even tenth
        else
            k = static_cast<size_t>(std::upper_bound(cdf.begin(), cdf.end(), (u - 0.1) / 0.9 * total) - cdf.begin());
        k = std::min(k, pool.size() - 1);
        const float weight = static_cast<float>(1.0 / (static_cast<double>(picks) * chance(k)));
        const LightSampleFn scaled = [&](size_t light, const Vec3& w, const Color& c) { (*each)(light, w, c * weight); };
        e += sample_light(pool[k], p, n, rng, samples, counters, each ? &scaled : nullptr, hair_start) * weight;
    }
    return e;
}

std::vector<Color> light_scales(const Scene& scene) {
    std::vector<Color> out;
    for (const Light& l : scene.lights) out.push_back(l.type == LightType::Mesh ? Color(1) : l.color);
    return out;
}

void DirectLighting::irradiance_parts(const Vec3& p, const Vec3& n, uint32_t object, const RandomStream& rng, int samples,
                                      Counters& counters, std::span<Color> out, float hair_start) const {
    for (size_t i = 0; i < scene_.lights.size(); ++i)
        out[i] = scene_.lights[i].lights(object) ? sample_light(i, p, n, rng, samples, counters, nullptr, hair_start, true) : Color(0);
}

Color DirectLighting::thin_or_parted_radiance(const Vec3& p, const Vec3& n, uint32_t object, const Color& reflect, const Color& transmit,
                                              const RandomStream& rng, int samples, Counters& counters, std::span<Color> parts) const {
    const bool through = transmit != Color(0);
    if (parts.empty()) {
        const Color front = reflect * irradiance(p, n, object, rng, samples, counters);
        return through ? front + transmit * irradiance(p, -n, object, back_side_stream(rng), samples, counters) : front;
    }
    irradiance_parts(p, n, object, rng, samples, counters, parts);
    std::vector<Color> back;  // translucent hits with light parts only (the lighting tool's)
    if (through) back.resize(parts.size()), irradiance_parts(p, -n, object, back_side_stream(rng), samples, counters, back);
    Color sum(0);
    for (size_t i = 0; i < parts.size(); ++i) {
        parts[i] = reflect * parts[i];
        if (through) parts[i] += transmit * back[i];
        sum += parts[i];
    }
    return sum;
}

Color DirectLighting::strand_radiance(const Hit& h, const Vec3& at, const Vec3& d, const RandomStream& rng, int samples, Counters& counters,
                                      std::span<Color> parts) const {
    const Fur& fur = *scene_.objects[h.object].fur;
    const Color albedo = fur.params.albedo(fur.v_of(h.prim, h.u));
    if (parts.empty()) return albedo * kInvPi * irradiance(at, -d, h.object, rng, samples, counters, true, nullptr, fur.max_width());
    irradiance_parts(at, -d, h.object, rng, samples, counters, parts, fur.max_width());
    Color sum(0);
    for (Color& x : parts) x = albedo * kInvPi * x, sum += x;
    return sum;
}

void DirectLighting::background_parts(const Vec3& dir, std::span<Color> out) const {
    for (size_t i = 0; i < scene_.lights.size(); ++i) {
        const Light& l = scene_.lights[i];
        out[i] = l.type != LightType::Sky ? Color(0) : l.sky_map ? l.sky_map->lookup(dir, l.sky_rotation) : Color(1);
    }
}

Color DirectLighting::background(const Vec3& dir) const {
    Color c(0);
    for (const auto& l : scene_.lights)
        if (l.type == LightType::Sky) c += l.sky_map ? l.color * l.sky_map->lookup(dir, l.sky_rotation) : l.color;
    return c;
}

namespace {

/// What every light's sampling of one point shares: where, which way, the shadow rays' test
/// and counts, and the per-direction callback.
struct LightQuery {
    const SceneAccel& accel;
    const Light& light;
    size_t index;
    Vec3 p, n;
    const RandomStream& rng;
    int samples;
    Counters& counters;
    const LightSampleFn* each;
    float hair_start;
    Color colour;  ///< the light's colour, or 1 for its unit contribution
    unsigned mask;
    uint32_t dim(uint32_t d) const { return static_cast<uint32_t>(kDimLight + 16 * index + d); }
    Vec2 stratum(int s) const {
        return stratified_2d(s, samples, rng.get(static_cast<uint64_t>(s), dim(1)), rng.get(static_cast<uint64_t>(s), dim(2)));
    }
    /// Whether the shadow ray towards `w` (up to `r`) is blocked, counting it.
    bool blocked(const Vec3& w, float r) const {
        ++counters.shadow_rays;
        return accel.occluded(p, w, r, hair_start, mask);
    }
};

Color sample_point_or_spot(const LightQuery& q) {
    const Light& l = q.light;
    Vec3 to = l.position - q.p;
    float r2 = dot(to, to), r = std::sqrt(r2);
    Vec3 w = to / r;
    float cos_x = dot(q.n, w);
    if (cos_x <= 0 || r2 == 0) return Color(0);
    float cone = 1;
    Color filter(1);
    if (l.type == LightType::Spot) {
        filter = spot_filter(l, -w);
        if (filter == Color(0)) return Color(0);
        const float along = std::clamp(dot(-w, l.direction), -1.0f, 1.0f);
        float angle = std::acos(along) * 180.0f / kPi;
        if (angle >= l.cone_angle + l.cone_falloff) return Color(0);
        if (angle > l.cone_angle) {
            float s = 1 - (angle - l.cone_angle) / l.cone_falloff;
            cone = s * s * (3 - 2 * s);  // smoothstep edge
        }
        if (l.cosine_power > 0) cone *= std::pow(std::max(along, 0.0f), l.cosine_power);
    }
    if (q.blocked(w, r)) return Color(0);
    Color e = q.colour * filter * (cone * cos_x / r2);
    if (q.each) (*q.each)(q.index, w, e);
    return e;
}

Color sample_distant(const LightQuery& q) {
    Vec3 w = -q.light.direction;
    float cos_x = dot(q.n, w);
    if (cos_x <= 0) return Color(0);
    if (q.blocked(w, INFINITY)) return Color(0);
    if (q.each) (*q.each)(q.index, w, q.colour * cos_x);
    return q.colour * cos_x;
}

Color sample_quad(const LightQuery& q) {
    const Light& l = q.light;
    Vec3 ln = cross(l.edge_u, l.edge_v);
    float area = length(ln);
    ln = ln / area;
    Color e(0);
    for (int s = 0; s < q.samples; ++s) {
        Vec2 uv = q.stratum(s);
        Vec3 to = l.corner + l.edge_u * uv.x + l.edge_v * uv.y - q.p;
        float r2 = dot(to, to), r = std::sqrt(r2);
        Vec3 w = to / r;
        float cos_x = dot(q.n, w), cos_l = -dot(ln, w);
        if (cos_x <= 0 || cos_l <= 0) continue;
        if (q.blocked(w, r)) continue;
        const Color L = l.texture ? q.colour * l.texture->at_uv(uv.x, uv.y) : q.colour;
        e += L * (cos_x * cos_l / r2);
        if (q.each) (*q.each)(q.index, w, L * (cos_x * cos_l / r2 * area / static_cast<float>(q.samples)));
    }
    return e * (area / static_cast<float>(q.samples));
}

Color sample_sky(const LightQuery& q) {
    const Light& l = q.light;
    Frame f(q.n);
    Color e(0);
    for (int s = 0; s < q.samples; ++s) {
        Vec2 uv = q.stratum(s);
        Vec3 w = f.to_world(cosine_hemisphere(uv.x, uv.y));
        if (q.blocked(w, INFINITY)) continue;
        Color L = l.sky_map ? q.colour * l.sky_map->lookup(w, l.sky_rotation) : q.colour;
        e += L;
        if (q.each) (*q.each)(q.index, w, L * (kPi / static_cast<float>(q.samples)));
    }
    // Cosine-weighted estimator of the integral of L cos: pi * mean(L).
    return e * (kPi / static_cast<float>(q.samples));
}

Color sample_mesh(const LightQuery& q, const Emitter& em, const Scene& scene) {
    if (em.area <= 0) return Color(0);
    const TriangleMesh& m = scene.objects[em.object].coarse;
    Color e(0);
    for (int s = 0; s < q.samples; ++s) {
        Vec2 uv = q.stratum(s);
        // First coordinate picks a triangle by area and is reused inside it, which keeps
        // the stratification across the whole emitter.
        float a = uv.x * em.area;
        size_t k = static_cast<size_t>(std::upper_bound(em.cdf.begin(), em.cdf.end(), a) - em.cdf.begin());
        k = std::min(k, em.prims.size() - 1);
        float lo = k ? em.cdf[k - 1] : 0, hi = em.cdf[k];
        float u1 = std::clamp((a - lo) / (hi - lo), 0.0f, 1.0f), u2 = uv.y;
        float su = std::sqrt(u1), bu = 1 - su, bv = u2 * su;  // uniform on the triangle
        SurfacePoint pt = surface_point(m, em.prims[k], bu, bv);
        Vec3 to = pt.p - q.p;
        float r2 = dot(to, to), r = std::sqrt(r2);
        Vec3 w = to / r;
        // Emits from the front (counter-clockwise) side only, like a real panel: a
        // two-sided emitter against a ceiling would light the ceiling behind it.
        float cos_x = dot(q.n, w), cos_l = -dot(pt.ng, w);
        if (cos_x <= 0 || cos_l <= 0) continue;
        if (q.blocked(w, r)) continue;
        const Color L = scene.materials[pt.material].emission_at(pt.uv);
        e += L * (cos_x * cos_l / r2);
        if (q.each) (*q.each)(q.index, w, L * (cos_x * cos_l / r2 * em.area / static_cast<float>(q.samples)));
    }
    return e * (em.area / static_cast<float>(q.samples));
}

}  // namespace

Color DirectLighting::sample_light(size_t index, const Vec3& p, const Vec3& n, const RandomStream& rng, int samples, Counters& counters,
                                   const LightSampleFn* each, float hair_start, bool unit) const {
    const Light& l = scene_.lights[index];
    const LightQuery q{accel_, l, index, p, n, rng, samples, counters, each, hair_start, unit ? Color(1) : l.color, shadow_ray_mask(l)};
    switch (l.type) {
        case LightType::Point:
        case LightType::Spot:
            return sample_point_or_spot(q);
        case LightType::Distant:
            return sample_distant(q);
        case LightType::Quad:
            return sample_quad(q);
        case LightType::Sky:
            return sample_sky(q);
        case LightType::Mesh:
            return sample_mesh(q, emitters_[index], scene_);
    }
    return Color(0);
}

}  // namespace bounce
