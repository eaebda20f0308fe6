#include "bounce/gather/ao_bake.h"

#include <algorithm>
#include <cmath>

#include "bounce/core/error.h"
#include "bounce/core/parallel.h"
#include "bounce/core/random.h"
#include "bounce/core/sampling.h"

namespace bounce {

namespace {

/// Which triangle covers each texel centre, and where: rasterized in uv space (first
/// triangle wins, so the result does not depend on threads).
struct Coverage {
    std::vector<int32_t> prim;  ///< -1 = no triangle
    std::vector<Vec2> bary;     ///< (u, v) barycentrics in Embree's convention
};

Coverage rasterize_uvs(const TriangleMesh& m, int res) {
    Coverage c;
    c.prim.assign(static_cast<size_t>(res) * res, -1);
    c.bary.resize(c.prim.size());
    const auto fres = static_cast<float>(res);
    for (size_t t = 0; t < m.triangle_count(); ++t) {
        const Vec2 &a = m.uvs[m.indices[3 * t]], &b = m.uvs[m.indices[3 * t + 1]], &d = m.uvs[m.indices[3 * t + 2]];
        const float det = (b.x - a.x) * (d.y - a.y) - (d.x - a.x) * (b.y - a.y);
        if (std::abs(det) < 1e-20f) continue;
        // Texel (x, y) has its centre at u = (x + 0.5) / res, v = 1 - (y + 0.5) / res.
        const float u0 = std::min({a.x, b.x, d.x}), u1 = std::max({a.x, b.x, d.x});
        const float v0 = std::min({a.y, b.y, d.y}), v1 = std::max({a.y, b.y, d.y});
        const int x0 = std::max(0, static_cast<int>(std::floor(u0 * fres - 0.5f))),
                  x1 = std::min(res - 1, static_cast<int>(std::ceil(u1 * fres)));
        const int y0 = std::max(0, static_cast<int>(std::floor((1 - v1) * fres - 0.5f))),
                  y1 = std::min(res - 1, static_cast<int>(std::ceil((1 - v0) * fres)));
        for (int y = y0; y <= y1; ++y)
            for (int x = x0; x <= x1; ++x) {
                const float pu = (static_cast<float>(x) + 0.5f) / fres, pv = 1 - (static_cast<float>(y) + 0.5f) / fres;
                const float bu = ((pu - a.x) * (d.y - a.y) - (d.x - a.x) * (pv - a.y)) / det;
                const float bv = ((b.x - a.x) * (pv - a.y) - (pu - a.x) * (b.y - a.y)) / det;
                if (bu < -1e-6f || bv < -1e-6f || bu + bv > 1 + 1e-6f) continue;
                const size_t k = static_cast<size_t>(y) * res + x;
                if (c.prim[k] >= 0) continue;
                c.prim[k] = static_cast<int32_t>(t);
                c.bary[k] = {bu, bv};
            }
    }
    return c;
}

}  // namespace

std::vector<float> bake_ao(const Scene& scene, const SceneAccel& accel, uint32_t id, const AoBakeSettings& s, Stats& stats,
                           ProgressSink* sink) {
    const TriangleMesh& m = scene.objects[id].visible();
    if (scene.objects[id].instance || scene.objects[id].prototype)  // its uvs are every placement's
        throw InputError(scene.path, "object " + scene.objects[id].name,
                         "is an instance or a prototype: its uvs are shared by every placement, its occlusion is not");
    if (m.uvs.empty()) throw InputError(scene.path, "object " + scene.objects[id].name, "has no uvs to bake occlusion into");
    const int res = s.resolution;
    const Coverage cov = rasterize_uvs(m, res);
    std::vector<float> ao(cov.prim.size(), 1.0f);
    Progress progress(sink, "bake ao", static_cast<uint64_t>(res));
    parallel_ranges(0, res, 1, [&](int y0, int y1) {
        Counters& counters = stats.local();
        for (int y = y0; y < y1; ++y, sink ? sink->check_cancel() : void()) {
            for (int x = 0; x < res; ++x) {
                const size_t k = static_cast<size_t>(y) * res + x;
                if (cov.prim[k] < 0) continue;
                const SurfacePoint sp = surface_point(m, static_cast<uint32_t>(cov.prim[k]), cov.bary[k].x, cov.bary[k].y);
                // Both sides could be the outside of an open mesh: bake the side the shading
                // normal faces, as the renderer shades it.
                const Frame frame(sp.n);
                const Vec3 origin = sp.p + sp.ng * (dot(sp.ng, sp.n) < 0 ? -1.0f : 1.0f) * accel.self_epsilon(sp.p);
                const RandomStream rng(0x0a0b, static_cast<uint64_t>(id) << 32 | static_cast<uint64_t>(k));
                int open = 0;
                for (int i = 0; i < s.rays; ++i) {
                    const Vec2 u = stratified_2d(i, s.rays, rng.get(static_cast<uint64_t>(i), 0), rng.get(static_cast<uint64_t>(i), 1));
                    const Vec3 d = frame.to_world(cosine_hemisphere(u.x, u.y));
                    ++counters.gather_rays;
                    open += !accel.fine().intersect(origin, d, 0, s.distance).valid();
                }
                ao[k] = static_cast<float>(open) / static_cast<float>(s.rays);
            }
            progress.add();
        }
    });
    // Dilate into uncovered texels (nearest covered one within 4 texels, ties by scan order).
    std::vector<float> out = ao;
    for (int y = 0; y < res; ++y)
        for (int x = 0; x < res; ++x) {
            const size_t k = static_cast<size_t>(y) * res + x;
            if (cov.prim[k] >= 0) continue;
            int best = 1 << 30;
            for (int dy = -4; dy <= 4; ++dy)
                for (int dx = -4; dx <= 4; ++dx) {
                    const int xx = x + dx, yy = y + dy;
                    if (xx < 0 || yy < 0 || xx >= res || yy >= res) continue;
                    const size_t j = static_cast<size_t>(yy) * res + xx;
                    if (cov.prim[j] >= 0 && dx * dx + dy * dy < best) best = dx * dx + dy * dy, out[k] = ao[j];
                }
        }
    return out;
}

}  // namespace bounce
