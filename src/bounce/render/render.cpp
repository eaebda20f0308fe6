#include "bounce/render/render.h"

#include <fmt/format.h>

#include <cmath>
#include <tbb/task_arena.h>

#include "bounce/accel/accel.h"
#include "bounce/core/error.h"
#include "bounce/gather/gather.h"
#include "bounce/lighting/lighting.h"
#include "bounce/radiosity/radiosity.h"
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

RadiositySettings radiosity_settings(const Scene& scene) {
    RadiositySettings s;
    s.texel_size = scene.render.radiosity_texel;
    s.light_samples = scene.render.radiosity_light_samples;
    return s;
}

namespace {

/// Radiosity textures for the gather: loaded from the folder when they match the scene,
/// otherwise baked (and saved there if a folder was named).
std::unique_ptr<RadiosityTextures> radiosity_for(const Scene& scene, const Materials& materials,
                                                 const DirectLighting& lighting, Stats& stats, ProgressSink* progress) {
    const std::string& dir = scene.render.radiosity_textures;
    RadiositySettings settings = radiosity_settings(scene);
    auto rt = std::make_unique<RadiosityTextures>();
    if (!dir.empty()) {
        PhaseTimer t(stats, "radiosity load");
        std::string why;
        if (RadiosityTextures::load(dir, scene, settings, *rt, why)) {
            stats.set("radiosity_reused", 1);
            return rt;
        }
        if (progress) std::fprintf(stderr, "radiosity textures in %s not reused: %s; baking\n", dir.c_str(), why.c_str());
    }
    {
        PhaseTimer t(stats, "radiosity bake");
        *rt = RadiosityTextures::bake(scene, materials, lighting, settings, stats, progress);
    }
    if (!dir.empty()) {
        PhaseTimer t(stats, "radiosity save");
        rt->save(dir);
    }
    stats.set("radiosity_reused", 0);
    return rt;
}

}  // namespace

std::string seed_table(const nlohmann::json& s) {
    auto clock = [](double secs) { return fmt::format("{}:{:06.3f}", static_cast<int>(secs) / 60, std::fmod(secs, 60.0)); };
    const auto& ph = s["phases_s"];
    auto phase = [&](const char* n) { return ph.contains(n) ? ph[n].get<double>() : 0.0; };
    double gathering = phase("gather") + phase("radiosity bake") + phase("radiosity load");
    double shading = phase("shading");
    double total = s["total_s"].get<double>();
    double pixels = s.value("pixels", 0.0);
    double rays = static_cast<double>(s["rays"]["gather"].get<uint64_t>());
    std::string per_record = s.contains("records") ? fmt::format("{}", s.value("rays_per_gather", 0)) : "-";
    std::string records = s.contains("records") ? fmt::format("{}", s["records"].get<double>()) : "-";
    return fmt::format("| gathering | shading | total | rays/record | records | rays/MP |\n"
                       "| {} | {} | {} | {} | {} | {:.1f} M |\n",
                       clock(gathering), clock(shading), clock(total), per_record, records,
                       pixels > 0 ? rays / pixels : 0.0);
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
        std::vector<Indirect> indirect;
        const bool gi = scene.render.gi != "none" || scene.render.ao;
        if (gi) {
            GatherSettings gs = gather_settings(scene);
            std::unique_ptr<RadiosityTextures> radiosity;
            if (scene.render.radiosity && !gs.ao_only)
                radiosity = radiosity_for(scene, materials, lighting, stats, progress);
            Gatherer gatherer(scene, *accel, materials, lighting, radiosity.get(), gs);
            uint64_t rays_before = stats.total().gather_rays;
            PhaseTimer t(stats, "gather");
            indirect = gather_every_fragment(scene, result.deep, gatherer, stats, progress);
            double secs = t.stop();
            uint64_t rays = stats.total().gather_rays - rays_before;
            stats.set("gather_rays_per_s", secs > 0 ? static_cast<double>(rays) / secs : 0.0);
            stats.set("gathers", static_cast<double>(result.deep.fragments.size()));
            stats.set("rays_per_gather", gatherer.grid().rays());
        }
        {
            PhaseTimer t(stats, "shading");
            result.image = shade(scene, result.deep, materials, lighting, gi ? &indirect : nullptr, stats, progress);
        }
    });
    stats.set("pixels", static_cast<double>(result.deep.pixel_count()));
    double mp = static_cast<double>(result.deep.pixel_count()) * 1e-6;
    stats.set("gather_rays_per_pixel", static_cast<double>(stats.total().gather_rays) / (mp * 1e6));
    auto& md = result.image.metadata;
    md["scene"] = scene.path;
    md["seed"] = std::to_string(scene.render.seed);
    md["deep_seed"] = std::to_string(result.deep.seed);
    md["spp"] = std::to_string(result.deep.spp);
    md["gi"] = scene.render.ao ? "ao" : scene.render.gi;
    md["rays"] = std::to_string(scene.render.rays);
    md["light_samples"] = std::to_string(scene.render.light_samples);
    md["scene_fingerprint"] = fmt::format("{:016x}", result.deep.scene_fingerprint);
    md["render_time_s"] = fmt::format("{:.3f}", stats.to_json()["total_s"].get<double>());
    return result;
}

}  // namespace bounce
