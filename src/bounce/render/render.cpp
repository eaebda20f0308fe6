#include "bounce/render/render.h"

#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <tbb/task_arena.h>

#include "bounce/accel/accel.h"
#include "bounce/cache/passes.h"
#include "bounce/core/error.h"
#include "bounce/core/parallel.h"
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

void add_records_layer(Image& image, const Camera& camera, const std::vector<Vec3>& positions) {
    const Layer* beauty = image.find("beauty");
    Layer& l = image.add_layer("records", {"records.R", "records.G", "records.B"});
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x)
            for (int c = 0; c < 3; ++c) image.at(l, x, y)[c] = 0.5f * std::min(1.0f, image.at(*beauty, x, y)[c]);
    CameraRays rays(camera);
    for (const Vec3& p : positions) {
        float px, py;
        if (!rays.project(p, px, py)) continue;
        int cx = static_cast<int>(std::floor(px)) - image.x0, cy = static_cast<int>(std::floor(py)) - image.y0;
        for (int y = cy - 1; y <= cy + 1; ++y)
            for (int x = cx - 1; x <= cx + 1; ++x)
                if (x >= 0 && y >= 0 && x < image.width && y < image.height)
                    for (int c = 0; c < 3; ++c) image.at(l, x, y)[c] = 1.0f;
    }
}

CacheSettings cache_settings(const Scene& scene) {
    const RenderSettings& r = scene.render;
    CacheSettings c;
    c.metric = r.metric;
    c.min_spacing = r.min_spacing;
    c.max_spacing = r.max_spacing;
    c.max_angle = r.max_angle;
    c.gradient_limit = r.gradient_limit;
    c.quality = r.quality;
    c.min_weight = r.min_weight;
    c.accuracy = r.accuracy;
    c.gradients = r.gradients;
    c.neighbour_clamp = r.neighbour_clamp;
    c.shading_reach = r.shading_reach;
    c.radius_scale = r.radius_scale;
    return c;
}

CacheFileInfo cache_file_info(const Scene& scene, int frame) {
    CacheFileInfo info;
    info.scene_fingerprint = scene.fingerprint({"objects", "materials", "lights"}, true);
    info.camera_fingerprint = scene.fingerprint({"camera"});
    const RenderSettings& r = scene.render;
    info.parameters = {{"metric", r.metric},       {"min_spacing", r.min_spacing}, {"max_spacing", r.max_spacing},
                       {"max_angle", r.max_angle}, {"gradient_limit", r.gradient_limit}, {"quality", r.quality},
                       {"min_weight", r.min_weight}, {"accuracy", r.accuracy}, {"rays", r.rays},
                       {"shading_reach", r.shading_reach}, {"radius_scale", r.radius_scale},
                       {"ao", r.ao},               {"ao_distance", r.ao_distance}, {"seed", r.seed}};
    info.frame = frame;
    return info;
}

namespace {

/// Loads `path` into `cache`, refusing a cache made for another scene or camera unless forced.
size_t load_cache(const std::string& path, const Scene& scene, bool force, IrradianceCache& cache) {
    CacheFile f = read_cache_file(path);
    CacheFileInfo want = cache_file_info(scene, 0);
    if (!force && f.info.scene_fingerprint != want.scene_fingerprint)
        throw InputError(path, "scene_fingerprint",
                         "cache was made for another scene (objects, materials or lights differ); --force uses it anyway");
    if (!force && f.info.camera_fingerprint != want.camera_fingerprint)
        throw InputError(path, "camera_fingerprint",
                         "cache was made for another camera (its spacing is in that camera's pixels); --force uses it anyway");
    if (!force && f.info.parameters.value("ao", false) != scene.render.ao)
        throw InputError(path, "parameters/ao", scene.render.ao ? "cache holds irradiance, not AO" : "cache holds AO, not irradiance");
    cache.set_luminance_floor(f.info.luminance_floor);
    for (const Record& r : f.records) cache.insert_loaded(r);
    return f.records.size();
}

/// Preview: each pixel takes the indirect light of the nearest pixel (on the lattices of the
/// current step, then coarser ones) that a finished sub-pass visited.
std::vector<Indirect> preview_indirect(const DeepBuffer& deep, const IrradianceCache& cache,
                                       const std::vector<uint8_t>& visited, int step) {
    std::vector<Indirect> out(deep.fragments.size());
    parallel_for_each_index(0, deep.height, [&](int wy) {
        for (int wx = 0; wx < deep.width; ++wx) {
            int x = wx + deep.x0, y = wy + deep.y0, lx = wx, ly = wy;
            for (int s = step; s <= (1 << 20); s *= 2) {
                int cx = x - x % s - deep.x0, cy = y - y % s - deep.y0;
                if (cx >= 0 && cy >= 0 && visited[static_cast<size_t>(cy) * deep.width + cx]) {
                    lx = cx, ly = cy;
                    break;
                }
            }
            auto src = deep.pixel(lx, ly);
            size_t first = deep.offsets[static_cast<size_t>(wy) * deep.width + wx];
            auto frags = deep.pixel(wx, wy);
            for (uint32_t k = 0; k < frags.size(); ++k) {
                const Fragment& f = src.empty() ? frags[k] : src[std::min<size_t>(k, src.size() - 1)];
                Interpolated in = cache.lookup(f.p_base, f.n_base, true);
                out[first + k] = {in.E, in.ao, in.bent, in.dir};
            }
        }
    });
    return out;
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
        std::unique_ptr<IrradianceCache> cache;
        if (gi) {
            GatherSettings gs = gather_settings(scene);
            gs.record_terms = scene.render.gi == "cache";  // brute force needs no gradients
            std::unique_ptr<RadiosityTextures> radiosity;
            if (scene.render.radiosity && !gs.ao_only)
                radiosity = radiosity_for(scene, materials, lighting, stats, progress);
            Gatherer gatherer(scene, *accel, materials, lighting, radiosity.get(), gs);
            uint64_t rays_before = stats.total().gather_rays;
            PhaseTimer t(stats, "gather");
            if (scene.render.gi == "cache") {
                cache = std::make_unique<IrradianceCache>(scene.bounds(), cache_settings(scene), gs.ao_only);
                if (!request.cache_in.empty() && !request.regather) {
                    PhaseTimer tl(stats, "cache read");
                    result.records_loaded = load_cache(request.cache_in, scene, request.force, *cache);
                }
                SubPassCallback after;
                std::vector<Color> direct_e;
                std::vector<uint8_t> visited;
                if (scene.render.preview && request.preview) {
                    direct_e = fragment_direct_irradiance(scene, result.deep, lighting, false, stats);
                    visited.assign(result.deep.pixel_count(), 0);
                    after = [&](const SubPass& sp, size_t, size_t) {
                        for (int wy = 0; wy < result.deep.height; ++wy)
                            for (int wx = 0; wx < result.deep.width; ++wx)
                                if (sp.contains(wx + result.deep.x0, wy + result.deep.y0))
                                    visited[static_cast<size_t>(wy) * result.deep.width + wx] = 1;
                        std::vector<Indirect> ind = preview_indirect(result.deep, *cache, visited, sp.step);
                        request.preview(shade(scene, result.deep, materials, lighting, &ind, stats, nullptr, &direct_e));
                    };
                }
                gathering_pass(scene, result.deep, gatherer, *cache, stats, progress, after, request.frame);
                result.records_new = cache->size() - result.records_loaded;
                stats.set("records_loaded", static_cast<double>(result.records_loaded));
                stats.set("records_new", static_cast<double>(result.records_new));
            } else {
                indirect = gather_every_fragment(scene, result.deep, gatherer, stats, progress);
                stats.set("gathers", static_cast<double>(result.deep.fragments.size()));
                stats.set("rays_per_gather", gatherer.grid().rays());
            }
            double secs = t.stop();
            uint64_t rays = stats.total().gather_rays - rays_before;
            stats.set("gather_rays_per_s", secs > 0 ? static_cast<double>(rays) / secs : 0.0);
        }
        {
            PhaseTimer t(stats, "shading");
            if (cache) {
                auto t0 = std::chrono::steady_clock::now();
                indirect = shading_pass(scene, result.deep, *cache, stats, progress);
                stats.set("interpolation_s", std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
            }
            result.image = shade(scene, result.deep, materials, lighting, gi ? &indirect : nullptr, stats, progress);
        }
        if (!cache && !request.cache_in.empty()) {  // --show records over a non-cache render
            cache = std::make_unique<IrradianceCache>(scene.bounds(), cache_settings(scene), scene.render.ao);
            result.records_loaded = load_cache(request.cache_in, scene, request.force, *cache);
        }
        if (cache && !request.cache_out.empty()) {
            PhaseTimer tw(stats, "cache write");
            write_cache_file(request.cache_out, cache->to_file(cache_file_info(scene, request.frame)));
        }
        if (cache) {
            std::vector<Vec3> positions;
            for (size_t i = 0; i < cache->size(); ++i) positions.push_back(cache->record(i).p);
            add_records_layer(result.image, scene.camera, positions);
        }
    });
    stats.set("pixels", static_cast<double>(result.deep.pixel_count()));
    if (result.deep.pixel_count() > 0)
        stats.set("gather_rays_per_pixel", static_cast<double>(stats.total().gather_rays) /
                                               static_cast<double>(result.deep.pixel_count()));
    auto& md = result.image.metadata;
    md["scene"] = scene.path;
    md["seed"] = std::to_string(scene.render.seed);
    md["deep_seed"] = std::to_string(result.deep.seed);
    md["spp"] = std::to_string(result.deep.spp);
    md["gi"] = scene.render.ao ? "ao" : scene.render.gi;
    md["rays"] = std::to_string(scene.render.rays);
    if (scene.render.gi == "cache")
        md["cache"] = fmt::format("metric={} min_spacing={} max_spacing={} max_angle={} gradient_limit={} quality={} min_weight={}",
                                  scene.render.metric, scene.render.min_spacing, scene.render.max_spacing,
                                  scene.render.max_angle, scene.render.gradient_limit, scene.render.quality,
                                  scene.render.min_weight);
    md["light_samples"] = std::to_string(scene.render.light_samples);
    md["scene_fingerprint"] = fmt::format("{:016x}", result.deep.scene_fingerprint);
    md["render_time_s"] = fmt::format("{:.3f}", stats.to_json()["total_s"].get<double>());
    return result;
}

}  // namespace bounce
