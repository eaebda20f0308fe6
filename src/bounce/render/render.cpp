#include "bounce/render/render.h"

#include <fmt/format.h>
#include <tbb/task_arena.h>

#include "bounce/accel/accel.h"
#include "bounce/core/error.h"
#include "bounce/lighting/lighting.h"
#include "bounce/shade/shade.h"

namespace bounce {

void validate_deep_for_scene(const DeepBuffer& deep, const Scene& scene, const std::string& path) {
    if (deep.scene_fingerprint != scene.fingerprint({"camera", "objects"}))
        throw InputError(path, "bounce:scene_fingerprint",
                         "deep file was made for another scene or camera; re-render visibility without --deep-in");
    for (size_t i = 0; i < deep.fragments.size(); ++i) {
        const Fragment& f = deep.fragments[i];
        if (f.material >= scene.materials.size() || f.object >= scene.objects.size())
            throw InputError(path, fmt::format("fragment {}", i), "material or object id out of range for this scene");
    }
}

RenderResult render(const Scene& scene, const RenderRequest& request, Stats& stats, ProgressSink* progress) {
    int threads = scene.render.threads > 0 ? scene.render.threads : tbb::this_task_arena::max_concurrency();
    tbb::task_arena arena(threads);
    stats.set("threads", threads);
    RenderResult result;
    arena.execute([&] {
        std::unique_ptr<SceneAccel> accel;
        {
            PhaseTimer t(stats, "build BVH");
            accel = std::make_unique<SceneAccel>(scene);
        }
        stats.set("ray_offset", accel->ray_offset());
        if (!request.deep_in.empty()) {
            PhaseTimer t(stats, "read deep");
            result.deep = read_deep(request.deep_in);
            validate_deep_for_scene(result.deep, scene, request.deep_in);
        } else {
            check_camera_sees_geometry(scene, *accel);
            PhaseTimer t(stats, "visibility");
            result.deep = render_visibility(scene, *accel, stats, progress);
        }
        if (!request.deep_out.empty()) {
            PhaseTimer t(stats, "write deep");
            write_deep(request.deep_out, result.deep);
        }
        Materials materials(scene);
        DirectLighting lighting(scene, *accel);
        {
            PhaseTimer t(stats, "shading");
            result.image = shade(scene, result.deep, materials, lighting, stats, progress);
        }
    });
    stats.set("pixels", static_cast<double>(result.deep.pixel_count()));
    auto& md = result.image.metadata;
    md["scene"] = scene.path;
    md["seed"] = std::to_string(result.deep.seed);
    md["spp"] = std::to_string(result.deep.spp);
    md["light_samples"] = std::to_string(scene.render.light_samples);
    md["scene_fingerprint"] = fmt::format("{:016x}", result.deep.scene_fingerprint);
    md["render_time_s"] = fmt::format("{:.3f}", stats.to_json()["total_s"].get<double>());
    return result;
}

}  // namespace bounce
