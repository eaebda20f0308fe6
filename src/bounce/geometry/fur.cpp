#include "bounce/geometry/fur.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <unordered_map>

#include "bounce/core/random.h"

namespace bounce {

float UvMap::at(const Vec2& uv) const {
    if (width <= 0 || height <= 0) return 1;
    const float u = uv.x - std::floor(uv.x), v = uv.y - std::floor(uv.y);
    const int x = std::min(width - 1, static_cast<int>(u * static_cast<float>(width)));
    const int y = std::min(height - 1, static_cast<int>((1 - v) * static_cast<float>(height)));
    return values[static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x)];
}

float FurParams::falloff(float v) const {
    return falloff_root + (1 - falloff_root) * std::pow(std::clamp(v, 0.0f, 1.0f), falloff_exponent);
}

size_t FurParams::memory_bytes(uint64_t strands) const {
    const auto s = static_cast<size_t>(segments);
    const size_t per_strand =
        (s + 1) * 4 * sizeof(float) + s * (sizeof(uint32_t) + 64) + 2 * sizeof(Vec3) + 2 * sizeof(Vec2) + sizeof(uint32_t);
    return static_cast<size_t>(strands) * per_strand;
}

size_t Fur::memory_bytes() const { return params.memory_bytes(strand_count()); }

Vec3 Fur::tangent(uint32_t segment) const {
    const float* a = &vertices[4 * static_cast<size_t>(segment_first[segment])];
    const Vec3 d = Vec3(a[4], a[5], a[6]) - Vec3(a[0], a[1], a[2]);
    const float l = length(d);
    return l > 0 ? d / l : root_n[strand_of(segment)];
}

namespace {

enum FurDim : uint32_t { kTriangle, kBaryA, kBaryB, kLength, kLeanAngle, kLeanAmount, kPhase, kKeep };

/// Area CDF over the surface's triangles.
std::vector<double> area_cdf(const TriangleMesh& m) {
    std::vector<double> cdf(m.triangle_count());
    double sum = 0;
    for (size_t t = 0; t < m.triangle_count(); ++t) cdf[t] = sum += m.triangle_area(t);
    return cdf;
}

/// Draws each strand towards its clump's guide (the first strand rooted in the same cell of
/// clump_size): control point k moves clump x s_k of the way to the guide's, s_k = k / segments,
/// so roots stay put and tips gather.
void clump(Fur& fur) {
    const FurParams& p = fur.params;
    const size_t per = static_cast<size_t>(fur.segments) + 1;
    std::unordered_map<uint64_t, size_t> guide;
    for (size_t s = 0; s < fur.strand_count(); ++s) {
        const Vec3 c = fur.root_p[s] / p.clump_size;
        uint64_t key = 0;
        for (float x : {c.x, c.y, c.z}) key = hash_combine(key, static_cast<uint64_t>(static_cast<int64_t>(std::floor(x))));
        const size_t g = guide.emplace(key, s).first->second;
        if (g == s) continue;
        for (size_t k = 1; k < per; ++k) {
            const float w = p.clump * static_cast<float>(k) / static_cast<float>(fur.segments);
            float* q = &fur.vertices[4 * (s * per + k)];
            const float* t = &fur.vertices[4 * (g * per + k)];
            for (int i = 0; i < 3; ++i) q[i] += w * (t[i] - q[i]);
        }
    }
}

}  // namespace

Fur grow_fur(const TriangleMesh& surface, const FurParams& params) {
    const auto t0 = std::chrono::steady_clock::now();
    Fur fur;
    fur.params = params;
    fur.segments = params.segments;
    const std::vector<double> cdf = area_cdf(surface);
    if (cdf.empty() || cdf.back() <= 0 || params.count == 0) return fur;
    const size_t per = static_cast<size_t>(params.segments) + 1;
    fur.vertices.reserve(params.count * per * 4);
    fur.root_p.reserve(params.count), fur.root_n.reserve(params.count), fur.root_uv.reserve(params.count);
    fur.root_tri.reserve(params.count), fur.root_bary.reserve(params.count);
    const Vec3 down(0, -1, 0);
    for (uint64_t i = 0; i < params.count; ++i) {
        const RandomStream rng(params.seed, i);
        // The root: a triangle by area, a uniform point on it.
        const double pick = static_cast<double>(rng.get(0, kTriangle)) * cdf.back();
        const size_t tri = std::min(cdf.size() - 1, static_cast<size_t>(std::upper_bound(cdf.begin(), cdf.end(), pick) - cdf.begin()));
        float a = rng.get(0, kBaryA), b = rng.get(0, kBaryB);
        if (a + b > 1) a = 1 - a, b = 1 - b;
        const SurfacePoint sp = surface_point(surface, static_cast<uint32_t>(tri), a, b);
        if (params.density_map && rng.get(0, kKeep) >= params.density_map->at(sp.uv)) continue;
        float len = params.length * (1 + params.length_variation * (2 * rng.get(0, kLength) - 1));
        if (params.length_map) len *= params.length_map->at(sp.uv);
        if (len <= 0) continue;
        // A frame about the root normal: the strand leans a little off it, curls about its
        // own axis and bends under gravity as it grows.
        const Frame frame(sp.n);
        const float lean_phi = 2 * kPi * rng.get(0, kLeanAngle), lean = params.lean * rng.get(0, kLeanAmount);
        Vec3 dir = frame.to_world(Vec3(std::sin(lean) * std::cos(lean_phi), std::sin(lean) * std::sin(lean_phi), std::cos(lean)));
        const float phase = 2 * kPi * rng.get(0, kPhase);
        const float step = len / static_cast<float>(params.segments);
        Vec3 axis = sp.p;
        const size_t strand = fur.root_p.size();
        for (int k = 0; k <= params.segments; ++k) {
            const float s = static_cast<float>(k) / static_cast<float>(params.segments);
            Vec3 q = axis;
            if (params.curl > 0) {
                // The helix grows from nothing at the root so the root stays on the surface.
                const float ang = phase + 2 * kPi * params.curl_turns * s;
                q = q + (frame.s * std::cos(ang) + frame.t * std::sin(ang)) * (params.curl * len * s);
            }
            const float w = params.width_root + (params.width_tip - params.width_root) * s;
            fur.vertices.insert(fur.vertices.end(), {q.x, q.y, q.z, 0.5f * w});
            axis = axis + dir * step;
            if (params.gravity > 0) dir = normalize(dir + down * (2 * params.gravity / static_cast<float>(params.segments)));
        }
        for (int k = 0; k < params.segments; ++k) fur.segment_first.push_back(static_cast<uint32_t>(strand * per + static_cast<size_t>(k)));
        fur.root_p.push_back(sp.p);
        fur.root_n.push_back(sp.n);
        fur.root_uv.push_back(sp.uv);
        fur.root_tri.push_back(static_cast<uint32_t>(tri));
        fur.root_bary.push_back(Vec2{a, b});
    }
    if (params.clump > 0) clump(fur);
    fur.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return fur;
}

namespace {

/// The frame a strand turns with: the root's normal, and its triangle's first edge made
/// perpendicular to it. False where the pose folds the triangle to an edge or a point.
bool root_frame(const TriangleMesh& m, uint32_t tri, const Vec3& n, std::array<Vec3, 3>& frame) {
    const Vec3 e = m.positions[m.indices[3 * tri + 1]] - m.positions[m.indices[3 * tri]];
    const Vec3 s = e - n * dot(e, n);
    const float l = length(s);
    if (!(l > 0) || !isfinite(n)) return false;
    frame = {s / l, cross(n, s / l), n};
    return true;
}

/// Strand `s` of `fur` (on `from`) carried to `to`: its control points into `out` (which may be
/// fur.vertices itself); returns where its root is now.
SurfacePoint carry_strand(const Fur& fur, size_t s, const TriangleMesh& from, const TriangleMesh& to, std::vector<float>& out) {
    const size_t per = static_cast<size_t>(fur.segments) + 1;
    const uint32_t tri = fur.root_tri[s];
    const Vec2 b = fur.root_bary[s];
    const SurfacePoint then = surface_point(from, tri, b.x, b.y), now = surface_point(to, tri, b.x, b.y);
    std::array<Vec3, 3> f, g;
    // A triangle folded flat keeps the strand's direction (nothing to turn it by).
    const bool turn = root_frame(from, tri, then.n, f) && root_frame(to, tri, now.n, g);
    for (size_t k = 0; k < per; ++k) {
        const size_t i = 4 * (s * per + k);
        const Vec3 d = Vec3(fur.vertices[i], fur.vertices[i + 1], fur.vertices[i + 2]) - fur.root_p[s];
        const Vec3 p = now.p + (turn ? g[0] * dot(d, f[0]) + g[1] * dot(d, f[1]) + g[2] * dot(d, f[2]) : d);
        out[i] = p.x, out[i + 1] = p.y, out[i + 2] = p.z;
    }
    return now;
}

bool same_pose(const TriangleMesh& from, const TriangleMesh& to) { return from.positions == to.positions && from.normals == to.normals; }

}  // namespace

bool same_triangles(const TriangleMesh& from, const TriangleMesh& to) {
    return from.indices == to.indices && from.positions.size() == to.positions.size();
}

void carry_fur(Fur& fur, const TriangleMesh& from, const TriangleMesh& to) {
    if (same_pose(from, to)) return;
    for (size_t s = 0; s < fur.strand_count(); ++s) {
        const SurfacePoint now = carry_strand(fur, s, from, to, fur.vertices);
        fur.root_p[s] = now.p, fur.root_n[s] = now.n, fur.root_uv[s] = now.uv;
    }
}

std::vector<float> carried_vertices(const Fur& fur, const TriangleMesh& from, const TriangleMesh& to) {
    std::vector<float> out = fur.vertices;
    if (!same_pose(from, to))
        for (size_t s = 0; s < fur.strand_count(); ++s) carry_strand(fur, s, from, to, out);
    return out;
}

Color kajiya_kay(const Vec3& t, const Vec3& wi, const Vec3& wo, const Color& albedo, float specular, float exponent) {
    const float ti = dot(t, wi), to = dot(t, wo);
    const float si = std::sqrt(std::max(0.0f, 1 - ti * ti)), so = std::sqrt(std::max(0.0f, 1 - to * to));
    // The mirror cone of wi about the strand keeps the tangential component: t.wo = -t.wi on it.
    const float cone = std::max(0.0f, -ti * to + si * so);
    constexpr float kDiffuse = 2 / (kPi * kPi);
    return albedo * (kDiffuse * si) + Color(specular * std::pow(cone, exponent));
}

Color hair_indirect(const Vec3& t, const Vec3& d, const Vec3& n, const Vec3& wo, const Color& e, const Color& albedo, float specular,
                    float exponent) {
    Color out = albedo * e * kInvPi;
    if (specular > 0) {
        // As surfaces do: a grazing mean direction carries no reliable direction (brdf.h).
        const float nd = dot(n, d);
        const bool grazing = nd < 0.05f;
        out += kajiya_kay(t, grazing ? n : d, wo, Color(0), specular, exponent) * (grazing ? e : e / nd);
    }
    return out;
}

}  // namespace bounce
