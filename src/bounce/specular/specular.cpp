#include "bounce/specular/specular.h"

#include <algorithm>
#include <cmath>

namespace bounce {

namespace {

constexpr float kMinWeight = 1e-4f;

bool negligible(const Color& w) { return std::max({w.x, w.y, w.z}) < kMinWeight; }

Color beer(const Color& absorption, float distance) {
    return {std::exp(-absorption.x * distance), std::exp(-absorption.y * distance), std::exp(-absorption.z * distance)};
}

}  // namespace

/// A ray of a path: where it leaves, where it goes, what it carries and what is left of it.
struct SpecularTracer::Branch {
    Vec3 o, d;
    Color weight;
    int bounces_left = 0;
    float travelled = 0;  ///< path length up to o
    float spread = 0;     ///< footprint growth per unit of length (the camera pixel's angle)
    float footprint0 = 0;
    const Material* medium = nullptr;  ///< the dielectric the ray travels inside (null: outside)
    PathKind kind = PathKind::Reflection;
    uint32_t fragment = 0;
};

SpecularTracer::SpecularTracer(const Scene& scene, const SceneAccel& accel, const DirectLighting& lighting, const Materials& materials,
                               int depth)
    : scene_(scene), accel_(accel), lighting_(lighting), materials_(materials), depth_(depth) {
    active_ = std::any_of(scene.materials.begin(), scene.materials.end(), [](const Material& m) { return m.is_specular(); });
}

Color SpecularTracer::quads_seen(const Vec3& o, const Vec3& d, float t_max) const {
    Color sum(0);
    for (const Light& l : scene_.lights) {
        if (l.type != LightType::Quad) continue;
        const Vec3 n = cross(l.edge_u, l.edge_v);
        const float facing = dot(d, n);
        if (facing >= 0) continue;  // it emits towards n only
        const float t = dot(l.corner - o, n) / facing;
        if (!(t > 0 && t < t_max)) continue;
        // (a, b) in the quad's frame: q = a edge_u + b edge_v, by the 2x2 normal equations.
        const Vec3 q = o + d * t - l.corner;
        const float uu = dot(l.edge_u, l.edge_u), uv = dot(l.edge_u, l.edge_v), vv = dot(l.edge_v, l.edge_v);
        const float qu = dot(q, l.edge_u), qv = dot(q, l.edge_v), det = uu * vv - uv * uv;
        const float a = (qu * vv - qv * uv) / det, b = (qv * uu - qu * uv) / det;
        if (a < 0 || a > 1 || b < 0 || b > 1) continue;
        sum += l.texture ? l.color * l.texture->at_uv(a, b) : l.color;
    }
    return sum;
}

SpecularTracer::Start SpecularTracer::start_of(const Fragment& f, const Vec3& d) const {
    // The camera ray's crossing of the coarse surface near the fragment: the paths then see one
    // surface throughout. A fragment's normal averages its subsamples' and its point is one of
    // them; at grazing angles the mismatch (a few degrees on a sphere) would trap refracted
    // light by total internal reflection that the true surface lets out.
    const float reach = 2 * std::max(accel_.ray_offset(), f.footprint);
    const Hit h = accel_.coarse().intersect(f.p - d * reach, d, 0, 2 * reach);
    if (h.valid() && !h.hair && h.object == f.object) {
        const SurfacePoint sp = scene_.objects[h.object].coarse_point(h.prim, h.u, h.v);
        return {sp.p, sp.n, sp.ng};
    }
    // The authored outside: the triangle's normal on its shading normals' side.
    const Vec3 outward = scene_.objects[f.object].visible_point(f.prim, 1.0f / 3, 1.0f / 3).ng;
    return {f.p, dot(f.n, outward) < 0 ? -f.n : f.n, outward};
}

Vec3 SpecularTracer::bumped(const Fragment& f, const Start& at, const Vec3& d) const {
    if (!scene_.materials[f.material].has_bump()) return at.n;
    // The map's tilt of the fragment's normal, carried over to the start's (which may face the
    // other way, and is the coarse surface's); lessened where the mirror direction would go
    // under the surface (a steep bump seen at a grazing angle), so every path leaves it.
    Vec3 tilt = materials_.surface(f.material, f.object, f.prim, f.p, f.uv, f.n, f.footprint).normal - f.n;
    if (dot(f.n, at.n) < 0) tilt = -tilt;
    const Vec3 above = dot(d, at.outward) < 0 ? at.outward : -at.outward;
    for (float share : {1.0f, 0.75f, 0.5f, 0.25f}) {
        const Vec3 n = normalize(at.n + tilt * share);
        if (isfinite(n) && dot(reflect(d, n), above) > 0) return n;
    }
    return at.n;
}

void SpecularTracer::trace(std::span<const Fragment> frags, const Vec3& eye, PixelPaths& out, Counters& counters) const {
    out.clear();
    out.seen_reflection.assign(frags.size(), Color(0));
    out.seen_refraction.assign(frags.size(), Color(0));
    out.base.assign(frags.size(), Color(1));
    if (!active_) return;
    for (uint32_t k = 0; k < frags.size(); ++k) {
        const Fragment& f = frags[k];
        const Material& m = scene_.materials[f.material];
        if (f.is_hair() || !m.is_specular()) continue;
        const Vec3 d = normalize(f.p - eye);
        Start at = start_of(f, d);
        at.n = bumped(f, at, d);
        const bool entering = dot(d, at.outward) < 0;
        const Vec3 n = entering ? at.n : -at.n;
        const SpecularSplit s = specular_split(m, std::max(-dot(d, n), 0.0f), entering);
        out.base[k] = s.base;
        Branch b;
        b.o = at.p, b.d = d, b.weight = Color(1), b.bounces_left = depth_;
        b.spread = f.footprint / std::max(f.depth, 1e-20f), b.footprint0 = f.footprint, b.fragment = k;
        split(b, at.p, n, entering, m, 0, out, counters);
    }
}

void SpecularTracer::split(const Branch& b, const Vec3& p, const Vec3& n, bool entering, const Material& m, float travelled,
                           PixelPaths& out, Counters& counters) const {
    if (b.bounces_left <= 0) return;
    const SpecularSplit s = specular_split(m, std::max(-dot(b.d, n), 0.0f), entering);
    const bool first = b.bounces_left == depth_;
    Branch r = b;
    r.o = p, r.travelled = travelled, r.bounces_left = b.bounces_left - 1;
    r.d = reflect(b.d, n), r.weight = b.weight * s.reflect;
    if (first) r.kind = PathKind::Reflection;
    if (!negligible(r.weight)) follow(r, out, counters);
    Branch t = r;
    t.weight = b.weight * s.transmit;
    if (first) t.kind = PathKind::Refraction;
    if (negligible(t.weight) || !refract(b.d, n, entering ? 1 / m.ior : m.ior, t.d)) return;
    t.medium = entering ? &m : nullptr;
    follow(t, out, counters);
}

void SpecularTracer::follow(const Branch& b, PixelPaths& out, Counters& counters) const {
    if (out.rays >= kMaxRaysPerPixel) return;
    ++out.rays;
    ++counters.specular_rays;
    const Hit h = accel_.trace(b.o, b.d, kRayReflect);
    Color weight = b.weight;
    if (b.medium && h.valid()) weight *= beer(b.medium->absorption, h.t);
    Color& seen = b.kind == PathKind::Reflection ? out.seen_reflection[b.fragment] : out.seen_refraction[b.fragment];
    seen += weight * quads_seen(b.o, b.d, h.t);
    if (!h.valid()) {
        seen += weight * lighting_.background(b.d);
        return;
    }
    if (h.hair) {
        // A strand (fur seen by reflections) shows the direct light on its side facing the ray,
        // as a gather's hit on it does; no bounce light, no further path.
        const RandomStream rng(kDimLight, out.rays, h.prim);
        seen += weight * lighting_.strand_radiance(h, b.o + b.d * h.t, b.d, rng, lighting_.settings().light_samples, counters);
        return;
    }
    const Object& obj = scene_.objects[h.object];
    const SurfacePoint sp = obj.coarse_point(h.prim, h.u, h.v);
    const Material& m = scene_.materials[sp.material];
    const bool entering = dot(b.d, sp.ng) < 0;
    const Vec3 n = entering ? sp.n : -sp.n, ng = entering ? sp.ng : -sp.ng;
    const float travelled = b.travelled + h.t;
    const Color base = weight * (m.is_specular() ? specular_split(m, std::max(-dot(b.d, n), 0.0f), entering).base : Color(1));
    if (!negligible(base) && out.sites.size() < kMaxSitesPerPixel) {
        PathSite s;
        Fragment& f = s.at;
        f.p = f.p_base = sp.p, f.n = f.n_base = n, f.ng = ng, f.uv = sp.uv;
        f.material = sp.material, f.object = h.object, f.prim = h.prim;
        f.depth = travelled, f.weight = 1, f.footprint = b.footprint0 + b.spread * travelled;
        s.weight = base, s.wo = -b.d, s.u = h.u, s.v = h.v, s.front = entering, s.kind = b.kind, s.fragment = b.fragment;
        out.sites.push_back(s);
    }
    if (m.is_specular()) {
        Branch next = b;
        next.weight = weight;
        split(next, sp.p, n, entering, m, travelled, out, counters);
    }
}

namespace {

/// A site's footprint narrowed by its neighbours': the distance to the same site (same index,
/// same object) of the pixels beside it, the nearest of the four, where that is less than the
/// cone over the path length. A curved mirror or a glass ball focuses the pixel's cone (a ball
/// lens brings it to a point just behind itself), which the cone does not know; the neighbours'
/// paths do. Where they spread it (a minified view) records sized by the wider footprint
/// measured worse (bench/specular: refraction 6.8 % against 5.3 %), so the cone stays the
/// largest. The nearest neighbour, because across an edge of what the mirror shows the other
/// side is far. At most 64 times narrower. Neighbours in the same tile only: the processes of an
/// MPI job hold their own tiles' fragments, and the result must not depend on how many there are.
void measure_footprints(std::vector<std::vector<Fragment>>& per_pixel, int width, int height, int tile) {
    std::vector<float> measured;
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            std::vector<Fragment>& mine = per_pixel[static_cast<size_t>(y) * width + x];
            measured.assign(mine.size(), INFINITY);
            for (auto [dx, dy] : {std::pair{1, 0}, std::pair{-1, 0}, std::pair{0, 1}, std::pair{0, -1}}) {
                const int nx = x + dx, ny = y + dy;
                if (nx < 0 || ny < 0 || nx >= width || ny >= height || nx / tile != x / tile || ny / tile != y / tile) continue;
                const std::vector<Fragment>& theirs = per_pixel[static_cast<size_t>(ny) * width + nx];
                for (size_t j = 0; j < mine.size() && j < theirs.size(); ++j)
                    if (theirs[j].object == mine[j].object) measured[j] = std::min(measured[j], length(theirs[j].p - mine[j].p));
            }
            for (size_t j = 0; j < mine.size(); ++j)
                if (std::isfinite(measured[j]) && measured[j] > 0)
                    mine[j].footprint = std::clamp(measured[j], mine[j].footprint / 64, mine[j].footprint);
        }
}

}  // namespace

DeepBuffer specular_sites(const Scene& scene, const DeepBuffer& deep, const SpecularTracer& tracer, int tile_size, Stats& stats,
                          ProgressSink* progress) {
    DeepBuffer sites;
    sites.full_width = deep.full_width, sites.full_height = deep.full_height;
    sites.x0 = deep.x0, sites.y0 = deep.y0, sites.width = deep.width, sites.height = deep.height;
    sites.spp = deep.spp, sites.seed = deep.seed, sites.scene_fingerprint = deep.scene_fingerprint;
    std::vector<std::vector<Fragment>> per_pixel(deep.pixel_count());
    const Vec3 eye = CameraRays(scene.camera).origin();
    for_each_pixel_in_tiles(deep, tile_size, progress, "specular paths", [&](int wx, int wy, size_t) {
        PixelPaths paths;
        tracer.trace(deep.pixel(wx, wy), eye, paths, stats.local());
        auto& mine = per_pixel[static_cast<size_t>(wy) * deep.width + wx];
        for (const PathSite& s : paths.sites) mine.push_back(s.at);
    });
    measure_footprints(per_pixel, deep.width, deep.height, std::max(1, tile_size));
    sites.offsets.assign(deep.pixel_count() + 1, 0);
    for (size_t i = 0; i < per_pixel.size(); ++i) sites.offsets[i + 1] = sites.offsets[i] + static_cast<uint32_t>(per_pixel[i].size());
    sites.fragments.reserve(sites.offsets.back());
    for (auto& v : per_pixel) sites.fragments.insert(sites.fragments.end(), v.begin(), v.end());
    return sites;
}

}  // namespace bounce
