// Issue 16's ray-side question: should secondary rays trace Embree's own subdivision geometry
// (RTC_GEOMETRY_TYPE_SUBDIVISION with a displacement function, tessellated by Embree at commit)
// or bounce's pre-tessellated coarse mesh (dice() at render.ray_level)? On the Catmull-Clark
// objects of a scene (default scenes/displaced/displaced.json), displaced by the same map, for
// each ray side: build time and Embree memory, the 99th percentile gap to the fine surface
// (what sets the ray offset), closest-hit rays per second from points on the fine surface with
// bounce's ray-origin offsetting (one thread, SceneAccel::trace's logic), and the AO those rays
// give against the same rays traced on the fine surface itself ("equal image"). Other objects
// are triangles in every side. Prints a Markdown table (docs/displacement.md quotes it).
//
//   bounce_ray_side [SCENE] [--points N] [--rays M] [--reference-level L]
#include <embree3/rtcore.h>
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <optional>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "bounce/core/random.h"
#include "bounce/core/sampling.h"
#include "bounce/dice/displacement.h"
#include "bounce/dice/subdivision.h"
#include "bounce/scene/scene_load.h"

namespace bounce {
namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

long long g_bytes = 0;  // Embree's allocations (one build at a time)
bool count_bytes(void*, ssize_t bytes, bool) {
    g_bytes += bytes;
    return true;
}

/// A quad face's patch (u, v) to its face-varying uv: bilinear over the corners, which is what
/// linear face-varying interpolation gives on a quad (dice's uvs).
struct DisplacedCage {
    const SubdivSurface* surface;
    std::vector<size_t> first_corner;  ///< per face
};

void displace(const RTCDisplacementFunctionNArguments* a) {
    const auto* cage = static_cast<const DisplacedCage*>(a->geometryUserPtr);
    const ControlMesh& c = cage->surface->control;
    const Displacement& d = cage->surface->displacement;
    const size_t k = cage->first_corner[a->primID];
    const Vec2 t[4] = {c.uvs[static_cast<size_t>(c.face_uvs[k])], c.uvs[static_cast<size_t>(c.face_uvs[k + 1])],
                       c.uvs[static_cast<size_t>(c.face_uvs[k + 2])], c.uvs[static_cast<size_t>(c.face_uvs[k + 3])]};
    for (unsigned i = 0; i < a->N; ++i) {
        const float u = a->u[i], v = a->v[i];
        const float w[4] = {(1 - u) * (1 - v), u * (1 - v), u * v, (1 - u) * v};
        Vec2 uv;
        for (int j = 0; j < 4; ++j) uv.x += w[j] * t[j].x, uv.y += w[j] * t[j].y;
        const float h = d.offset(uv);
        a->P_x[i] += h * a->Ng_x[i];
        a->P_y[i] += h * a->Ng_y[i];
        a->P_z[i] += h * a->Ng_z[i];
    }
}

void attach_triangles(RTCDevice device, RTCScene scene, const TriangleMesh& m) {
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* v = static_cast<float*>(
        rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), m.positions.size()));
    std::memcpy(v, m.positions.data(), m.positions.size() * sizeof(Vec3));
    auto* idx = static_cast<uint32_t*>(
        rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(uint32_t), m.triangle_count()));
    std::memcpy(idx, m.indices.data(), m.indices.size() * sizeof(uint32_t));
    rtcCommitGeometry(g);
    rtcAttachGeometry(scene, g);
    rtcReleaseGeometry(g);
}

void attach_subdivision(RTCDevice device, RTCScene scene, const DisplacedCage& cage, float rate) {
    const ControlMesh& c = cage.surface->control;
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_SUBDIVISION);
    auto* faces =
        static_cast<uint32_t*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_FACE, 0, RTC_FORMAT_UINT, sizeof(uint32_t), c.face_count()));
    for (size_t f = 0; f < c.face_count(); ++f) faces[f] = static_cast<uint32_t>(c.face_sizes[f]);
    auto* idx = static_cast<uint32_t*>(
        rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT, sizeof(uint32_t), c.face_vertices.size()));
    for (size_t k = 0; k < c.face_vertices.size(); ++k) idx[k] = static_cast<uint32_t>(c.face_vertices[k]);
    auto* v = static_cast<float*>(
        rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), c.positions.size()));
    std::memcpy(v, c.positions.data(), c.positions.size() * sizeof(Vec3));
    rtcSetGeometrySubdivisionMode(
        g, 0, cage.surface->boundary == SubdivBoundary::EdgeOnly ? RTC_SUBDIVISION_MODE_SMOOTH_BOUNDARY : RTC_SUBDIVISION_MODE_PIN_CORNERS);
    rtcSetGeometryTessellationRate(g, rate);
    if (cage.surface->displacement.active()) {
        rtcSetGeometryUserData(g, const_cast<DisplacedCage*>(&cage));
        rtcSetGeometryDisplacementFunction(g, displace);
    }
    rtcCommitGeometry(g);
    rtcAttachGeometry(scene, g);
    rtcReleaseGeometry(g);
}

/// A committed ray side with SceneAccel's offsetting (accel.cpp), closest hits only.
struct Side {
    std::string name;
    RTCScene scene = nullptr;
    double build_s = 0;
    long long bytes = 0;
    float delta = 0, min_eps = 0, gap99 = 0;

    float hit(const Vec3& o, const Vec3& d, float tnear, float tfar) const {
        RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        RTCRayHit rh{};
        rh.ray = {o.x, o.y, o.z, tnear, d.x, d.y, d.z, 0, tfar, 0xffffffffu, 0, 0};
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(scene, &ctx, &rh);
        return rh.hit.geomID == RTC_INVALID_GEOMETRY_ID ? INFINITY : rh.ray.tfar;
    }
    float self_epsilon(const Vec3& p) const { return std::max(1e-5f * std::max({std::abs(p.x), std::abs(p.y), std::abs(p.z)}), min_eps); }
    float offset_start(const Vec3& p, const Vec3& d) const {
        const Vec3 o = p - d * delta;
        float best = -1, tn = 0;
        for (int i = 0; i < 8; ++i) {
            const float t = hit(o, d, tn, 2 * delta);
            if (!std::isfinite(t)) break;
            if (best < 0 || std::abs(t - delta) < std::abs(best - delta)) best = t;
            if (t >= delta) break;
            tn = std::nextafter(t, INFINITY) + 1e-6f * delta;
        }
        return best >= 0 ? best + 1e-4f * delta : delta;
    }
    /// Distance from p to the first hit along d, leaving the fine surface (SceneAccel::trace).
    float trace(const Vec3& p, const Vec3& d) const {
        const float first = hit(p, d, self_epsilon(p), INFINITY);
        if (!(first < delta)) return first;
        return std::max(0.0f, hit(p - d * delta, d, offset_start(p, d), INFINITY) - delta);
    }
};

struct Probe {
    Vec3 p, n;
};

/// Points spread by area over the fine surfaces, with their (displaced) vertex normals.
std::vector<Probe> probes(const std::vector<TriangleMesh>& fine, size_t count) {
    std::vector<std::pair<const TriangleMesh*, size_t>> tris;
    std::vector<double> cdf;
    double total = 0;
    for (const TriangleMesh& m : fine)
        for (size_t t = 0; t < m.triangle_count(); ++t) {
            total += m.triangle_area(t);
            tris.push_back({&m, t});
            cdf.push_back(total);
        }
    RandomStream rng(16, 1);
    std::vector<Probe> out;
    for (size_t i = 0; i < count; ++i) {
        const double x = rng.get(i, 0) * total;
        const size_t k = static_cast<size_t>(std::lower_bound(cdf.begin(), cdf.end(), x) - cdf.begin());
        const auto& [m, t] = tris[std::min(k, tris.size() - 1)];
        float a = rng.get(i, 1), b = rng.get(i, 2);
        if (a + b > 1) a = 1 - a, b = 1 - b;
        const uint32_t* v = &m->indices[3 * t];
        const Vec3 p = m->positions[v[0]] * (1 - a - b) + m->positions[v[1]] * a + m->positions[v[2]] * b;
        const Vec3 n = normalize(m->normals[v[0]] * (1 - a - b) + m->normals[v[1]] * a + m->normals[v[2]] * b);
        out.push_back({p, n});
    }
    return out;
}

/// The offset distance SceneAccel would use: 4 x the 99th percentile of the probes' distances
/// to this side's surface along their normals, at least 1e-4 of the diagonal.
void set_offset(Side& side, const std::vector<Probe>& ps, float diag) {
    side.min_eps = 1e-7f * diag;
    std::vector<float> gaps;
    for (const Probe& q : ps) {
        const float up = side.hit(q.p, q.n, 0, 0.05f * diag), down = side.hit(q.p, -q.n, 0, 0.05f * diag);
        const float g = std::min(up, down);
        if (std::isfinite(g)) gaps.push_back(g);
    }
    if (!gaps.empty()) {
        auto at = gaps.begin() + static_cast<std::ptrdiff_t>(0.99 * static_cast<double>(gaps.size() - 1));
        std::nth_element(gaps.begin(), at, gaps.end());
        side.gap99 = *at;
    }
    side.delta = std::max(1e-4f * diag, 4 * side.gap99);
}

struct Result {
    std::vector<float> ao;  ///< per probe: the unoccluded fraction within the AO distance
    double seconds = 0;
    size_t rays = 0;
};

Result ambient_occlusion(const Side& side, const std::vector<Probe>& ps, int rays, float distance) {
    Result r;
    r.ao.resize(ps.size());
    const auto t0 = std::chrono::steady_clock::now();
    for (size_t i = 0; i < ps.size(); ++i) {
        const Frame frame(ps[i].n);
        const RandomStream rng(17, i);
        int open = 0;
        for (int j = 0; j < rays; ++j) {
            const Vec2 u = stratified_2d(j, rays, rng.get(static_cast<uint64_t>(j), 0), rng.get(static_cast<uint64_t>(j), 1));
            const Vec3 d = frame.to_world(cosine_hemisphere(u.x, u.y));
            open += side.trace(ps[i].p, d) > distance;
        }
        r.ao[i] = static_cast<float>(open) / static_cast<float>(rays);
    }
    r.seconds = seconds_since(t0);
    r.rays = ps.size() * static_cast<size_t>(rays);
    return r;
}

int run(int argc, char** argv) {
    std::string path = std::string(BOUNCE_SOURCE_DIR) + "/scenes/displaced/displaced.json";
    size_t points = 20000;
    int rays = 64, ref_level = 5;
    // A whole number in [lo, hi], or nullopt.
    auto count = [](const char* text, long lo, long hi) -> std::optional<long> {
        char* end = nullptr;
        errno = 0;
        const long v = std::strtol(text, &end, 10);
        if (errno || end == text || *end || v < lo || v > hi) return std::nullopt;
        return v;
    };
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        std::optional<long> v;
        if (a == "--points" && i + 1 < argc && (v = count(argv[++i], 1, 10'000'000)))
            points = static_cast<size_t>(*v);
        else if (a == "--rays" && i + 1 < argc && (v = count(argv[++i], 1, 1 << 16)))
            rays = static_cast<int>(*v);
        else if (a == "--reference-level" && i + 1 < argc && (v = count(argv[++i], 1, 7)))
            ref_level = static_cast<int>(*v);
        else if (!a.empty() && a[0] != '-')
            path = a;
        else {
            std::fprintf(stderr,
                         "bounce_ray_side: bad argument %s; usage: bounce_ray_side [SCENE] [--points 1..1e7] "
                         "[--rays 1..65536] [--reference-level 1..7]\n",
                         argv[i]);
            return 2;
        }
    }
    const Scene scene = load_scene(path);
    // Catmull-Clark cages, refined once where they are not all quads (the same limit surface;
    // Embree's patch (u, v) of a non-quad face is not the bilinear one displace() assumes).
    std::vector<SubdivSurface> cages;
    std::vector<const Object*> others;
    for (const Object& o : scene.objects) {
        if (!o.surface || o.surface->scheme != SubdivScheme::CatmullClark) {
            others.push_back(&o);
            continue;
        }
        SubdivSurface s = *o.surface;
        const auto& sizes = s.control.face_sizes;
        if (!std::all_of(sizes.begin(), sizes.end(), [](int n) { return n == 4; })) s.control = refine_cage(s, 1);
        std::printf("%s: cage of %zu quads\n", o.name.c_str(), s.control.face_count());
        cages.push_back(std::move(s));
    }
    if (cages.empty()) {
        std::fprintf(stderr, "%s: no Catmull-Clark object to compare on\n", path.c_str());
        return 2;
    }
    std::vector<DisplacedCage> displaced;
    for (const SubdivSurface& c : cages) {
        DisplacedCage d{&c, {}};
        for (size_t f = 0, k = 0; f < c.control.face_count(); k += static_cast<size_t>(c.control.face_sizes[f++]))
            d.first_corner.push_back(k);
        displaced.push_back(std::move(d));
    }
    Bounds bounds;
    for (const Object& o : scene.objects) bounds.extend(o.coarse.bounds());
    const float diag = length(bounds.diagonal());
    const float ao_distance = scene.render.indirect.ao_distance > 0 ? scene.render.indirect.ao_distance : 0.1f * diag;

    RTCDevice device = rtcNewDevice("threads=1");
    rtcSetDeviceMemoryMonitorFunction(device, count_bytes, nullptr);
    // One side: the cages as Embree subdivision geometry at `rate`, or diced at `level`.
    auto build = [&](const std::string& name, int level, float rate) {
        Side s;
        s.name = name;
        const long long before = g_bytes;
        const auto t0 = std::chrono::steady_clock::now();
        s.scene = rtcNewScene(device);
        rtcSetSceneBuildQuality(s.scene, RTC_BUILD_QUALITY_HIGH);
        rtcSetSceneFlags(s.scene, RTC_SCENE_FLAG_ROBUST);
        for (size_t i = 0; i < cages.size(); ++i) {
            if (rate > 0)
                attach_subdivision(device, s.scene, displaced[i], rate);
            else
                attach_triangles(device, s.scene, dice(cages[i], level));
        }
        for (const Object* o : others) attach_triangles(device, s.scene, o->coarse);
        rtcCommitScene(s.scene);
        s.build_s = seconds_since(t0);
        s.bytes = g_bytes - before;
        return s;
    };

    double quads = 0;
    for (const SubdivSurface& c : cages) quads += static_cast<double>(c.control.face_count());
    if (2 * quads * std::pow(4.0, ref_level) > 1e8) {
        std::fprintf(stderr, "bounce_ray_side: %s: level %d would dice %.3g triangles (limit 1e8): lower --reference-level\n", path.c_str(),
                     ref_level, 2 * quads * std::pow(4.0, ref_level));
        return 2;
    }
    std::vector<TriangleMesh> fine;
    for (const SubdivSurface& c : cages) fine.push_back(dice(c, ref_level));
    const std::vector<Probe> ps = probes(fine, points);
    Side ref = build(fmt::format("fine surface (level {})", ref_level), ref_level, 0);
    set_offset(ref, ps, diag);
    const Result truth = ambient_occlusion(ref, ps, rays, ao_distance);
    double mean = 0;
    for (float a : truth.ao) mean += a;
    mean /= static_cast<double>(truth.ao.size());

    std::printf("%s: %zu cage(s), %zu points on the level-%d surface, %d AO rays each (distance %.3g), 1 thread\n\n", path.c_str(),
                cages.size(), points, ref_level, rays, static_cast<double>(ao_distance));
    std::printf("| ray side | build | Embree memory | gap 99th pct | offset | rays/s | AO vs fine surface (rel. RMSE) | AO bias |\n");
    std::printf("|---|---|---|---|---|---|---|---|\n");
    auto row = [&](Side& s) {
        if (s.delta == 0) set_offset(s, ps, diag);
        const Result r = ambient_occlusion(s, ps, rays, ao_distance);
        double se = 0, bias = 0;
        for (size_t i = 0; i < r.ao.size(); ++i) {
            const double e = static_cast<double>(r.ao[i]) - truth.ao[i];
            se += e * e, bias += e;
        }
        const double n = static_cast<double>(r.ao.size());
        std::printf("| %s | %.3f s | %.1f MiB | %.3g | %.3g | %.2f M | %.2f %% | %+.2f %% |\n", s.name.c_str(), s.build_s,
                    static_cast<double>(s.bytes) / (1 << 20), static_cast<double>(s.gap99), static_cast<double>(s.delta),
                    static_cast<double>(r.rays) / r.seconds * 1e-6, 100 * std::sqrt(se / n) / mean, 100 * bias / n / mean);
        rtcReleaseScene(s.scene);
    };
    for (int level = 1; level <= 4; ++level) {
        Side s = build(fmt::format("bounce: diced at level {}", level), level, 0);
        row(s);
    }
    for (float rate : {2.0f, 4.0f, 8.0f, 16.0f}) {
        Side s = build(fmt::format("Embree subdivision, rate {:g}", rate), 0, rate);
        row(s);
    }
    row(ref);
    rtcReleaseDevice(device);
    return 0;
}

}  // namespace
}  // namespace bounce

int main(int argc, char** argv) {
    try {
        return bounce::run(argc, argv);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "bounce_ray_side: %s\n", e.what());
        return 2;
    }
}
