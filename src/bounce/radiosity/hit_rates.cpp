#include "bounce/radiosity/hit_rates.h"

#include <mutex>

#include "bounce/core/parallel.h"
#include "bounce/core/random.h"
#include "bounce/core/sampling.h"
#include "bounce/deep/deep_buffer.h"

namespace bounce {

HitProbe probe_gather_hits(const Scene& scene, const SceneAccel& accel, int grid, int rays) {
    const Camera& cam = scene.camera;
    const int columns = std::max(1, grid),
              rows = std::max(1, static_cast<int>(std::lround(static_cast<double>(grid) * cam.height / cam.width)));
    const CameraRays camera(cam);
    std::vector<uint64_t> hits(scene.objects.size(), 0);
    std::mutex merge;
    parallel_ranges(0, rows, 1, [&](int lo, int hi) {
        std::vector<uint64_t> mine(scene.objects.size(), 0);
        for (int r = lo; r < hi; ++r)
            for (int c = 0; c < columns; ++c) {
                const float px = (static_cast<float>(c) + 0.5f) * static_cast<float>(cam.width) / static_cast<float>(columns),
                            py = (static_cast<float>(r) + 0.5f) * static_cast<float>(cam.height) / static_cast<float>(rows);
                const Vec3 d = normalize(camera.direction(px, py));
                const Hit seen = accel.trace(camera.origin(), d, kRayCamera);
                if (!seen.valid() || seen.hair) continue;
                const SurfacePoint sp = scene.objects[seen.object].coarse_point(seen.prim, seen.u, seen.v);
                const Frame frame(dot(sp.ng, d) < 0 ? sp.ng : -sp.ng);
                const RandomStream rng(0x9a7e, static_cast<uint64_t>(r) * 65536u + static_cast<uint64_t>(c));
                for (int k = 0; k < rays; ++k) {
                    const Hit h = accel.trace(sp.p, frame.to_world(cosine_hemisphere(rng.get(static_cast<uint64_t>(k), 0),
                                                                                     rng.get(static_cast<uint64_t>(k), 1))));
                    if (h.valid() && !h.hair) ++mine[h.object];
                }
            }
        const std::lock_guard lock(merge);  // sums of counts: the same in any order
        for (size_t o = 0; o < hits.size(); ++o) hits[o] += mine[o];
    });
    HitProbe probe;
    probe.hits.assign(hits.begin(), hits.end());
    probe.slots = static_cast<double>(columns) * rows * std::max(1, rays);
    return probe;
}

}  // namespace bounce
