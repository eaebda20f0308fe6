#include "bounce/render/render.h"

#include <fmt/format.h>
#include <sys/resource.h>
#include <unistd.h>

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
#include "bounce/scene/params.h"
#include "bounce/shade/layers.h"
#include "bounce/shade/shade.h"

namespace bounce {

void validate_deep_for_scene(const DeepBuffer& deep, const Scene& scene, const std::string& path) {
    if (deep.scene_fingerprint != scene.visibility_fingerprint())
        throw InputError(path, "bounce:scene_fingerprint",
                         "deep file was made for another scene or camera (or dicing of its subdivision surfaces); re-render visibility without --deep-in");
    for (size_t i = 0; i < deep.fragments.size(); ++i) {
        const Fragment& f = deep.fragments[i];
        if (f.material >= scene.materials.size() || f.object >= scene.objects.size())
            throw InputError(path, fmt::format("fragment {}", i), "material or object id out of range for this scene");
        if (f.is_hair() && !scene.objects[f.object].fur)
            throw InputError(path, fmt::format("fragment {}", i), "a hair fragment of an object without fur");
        if (!f.is_hair() && f.prim >= scene.objects[f.object].visible().triangle_count())
            throw InputError(path, fmt::format("fragment {}", i), "triangle id out of range for this scene");
    }
}

int crop_margin(const Scene& scene) {
    const CacheSettings& c = scene.render.cache;
    return static_cast<int>(std::ceil(c.max_spacing * c.shading_reach)) + 1;
}

double estimate_render_bytes(const Scene& scene) {
    auto w = frame_window(scene);
    const double pixels = static_cast<double>(w[1] - w[0]) * (w[3] - w[2]);
    // About 1.3 fragments per pixel (edges), the deep buffer's offsets, ~24 float channels of
    // image layers, and per-fragment indirect light and direct radiance.
    const double per_fragment = sizeof(Fragment) + sizeof(Indirect) + sizeof(Color);
    return pixels * (1.3 * per_fragment + sizeof(uint32_t) + 24 * sizeof(float));
}

namespace {

/// Memory this process may use: the smaller of the machine's physical memory and any address
/// space limit.
double available_bytes() {
    double phys = static_cast<double>(sysconf(_SC_PHYS_PAGES)) * static_cast<double>(sysconf(_SC_PAGE_SIZE));
    rlimit rl{};
    if (getrlimit(RLIMIT_AS, &rl) == 0 && rl.rlim_cur != RLIM_INFINITY) phys = std::min(phys, static_cast<double>(rl.rlim_cur));
    return phys;
}

/// Radiosity textures for the gather: loaded from the folder when they match the scene,
/// otherwise laid out to be baked lazily, triangle side by side, as gather rays hit them.
std::unique_ptr<RadiosityTextures> radiosity_for(const Scene& scene, const Materials& materials,
                                                 const DirectLighting& lighting, Stats& stats, ProgressSink* progress) {
    const RadiositySettings& settings = scene.render.radiosity;
    auto rt = std::make_unique<RadiosityTextures>();
    if (!settings.folder.empty()) {
        PhaseTimer t(stats, "radiosity load");
        std::string why;
        if (RadiosityTextures::load(settings.folder, scene, settings, materials, lighting, *rt, why)) {
            stats.set("radiosity_reused", 1);
            return rt;
        }
        if (progress)
            std::fprintf(stderr, "radiosity textures in %s not reused: %s; baking\n", settings.folder.c_str(), why.c_str());
    }
    *rt = RadiosityTextures::lazy(scene, materials, lighting, settings);
    stats.set("radiosity_reused", 0);
    return rt;
}

/// The scene loader's dicing of subdivision surfaces and growing of fur, as phases with their sizes.
void report_dicing(const Scene& scene, Stats& stats) {
    double seconds = 0, micropolygons = 0, ray_triangles = 0;
    int level = 0;
    for (const Object& o : scene.objects) {
        if (o.dicing_level == 0) continue;
        seconds += o.dicing_seconds;
        micropolygons += static_cast<double>(o.visible().triangle_count());
        ray_triangles += static_cast<double>(o.coarse.triangle_count());
        level = std::max(level, o.dicing_level);
    }
    double fur_seconds = 0, strands = 0, segments = 0, fur_bytes = 0;
    for (const Object& o : scene.objects)
        if (o.fur) {
            fur_seconds += o.fur->seconds;
            strands += static_cast<double>(o.fur->strand_count());
            segments += static_cast<double>(o.fur->segment_count());
            fur_bytes += static_cast<double>(o.fur->memory_bytes());
        }
    if (strands > 0) {
        stats.add_phase("fur", fur_seconds);
        stats.set("fur_strands", strands);
        stats.set("fur_segments", segments);
        stats.set("fur_bytes", fur_bytes);
    }
    if (level == 0) return;
    stats.add_phase("dicing", seconds);
    stats.set("dicing_level", level);
    stats.set("micropolygons", micropolygons);
    stats.set("ray_triangles", ray_triangles);
}

/// Saves the textures when this render baked sides the folder did not hold.
void save_radiosity(const RadiosityTextures& rt, size_t baked_before, const Scene& scene, Stats& stats) {
    const size_t baked = rt.baked_sides();
    stats.set("radiosity_sides_baked", static_cast<double>(baked - baked_before));
    stats.set("radiosity_sides", static_cast<double>(rt.sides()));
    if (scene.render.radiosity.folder.empty() || baked == baked_before) return;
    PhaseTimer t(stats, "radiosity save");
    rt.save(scene.render.radiosity.folder);
}

/// Forwards progress to the caller's sink (if any) and carries the request's cancel token.
class CancellableSink : public ProgressSink {
public:
    CancellableSink(ProgressSink* inner, const CancelToken* token) : inner_(inner) { cancel = token; }
    void update(const std::string& name, uint64_t done, uint64_t total, double elapsed) override {
        if (inner_) inner_->update(name, done, total, elapsed);
    }
    void finish(const std::string& name, uint64_t total, double elapsed) override {
        if (inner_) inner_->finish(name, total, elapsed);
    }

private:
    ProgressSink* inner_;
};

std::array<int, 4> grow(const std::array<int, 4>& w, int m, const DeepBuffer& within) {
    return {std::max(within.x0, w[0] - m), std::min(within.x0 + within.width, w[1] + m),
            std::max(within.y0, w[2] - m), std::min(within.y0 + within.height, w[3] + m)};
}

/// The window of pixels the render gathers in (the crop and its margin) as a deep buffer.
DeepBuffer gathered_window(const Scene& scene, const RenderRequest& request, const SceneAccel& accel, Stats& stats,
                           ProgressSink* sink) {
    const std::array<int, 4> crop = frame_window(scene);
    const int margin = scene.render.visibility.has_crop() && scene.render.indirect.gi == GiMode::Cache ? crop_margin(scene) : 0;
    if (!request.deep_in.empty() || request.deep) {
        DeepBuffer deep;
        if (request.deep) {
            deep = *request.deep;
        } else {
            PhaseTimer t(stats, "read deep");
            deep = read_deep(request.deep_in);
        }
        validate_deep_for_scene(deep, scene, request.deep_in.empty() ? "the session's deep buffer" : request.deep_in);
        // Without a crop, a deep file of a window renders that window.
        if (!scene.render.visibility.has_crop()) return deep;
        if (crop[0] < deep.x0 || crop[2] < deep.y0 || crop[1] > deep.x0 + deep.width || crop[3] > deep.y0 + deep.height)
            throw InputError(request.deep_in, "", fmt::format("the deep file covers pixels [{}, {}) x [{}, {}), not the crop",
                                                              deep.x0, deep.x0 + deep.width, deep.y0, deep.y0 + deep.height));
        return sub_window(deep, grow(crop, margin, deep));
    }
    check_camera_sees_geometry(scene, accel);
    PhaseTimer t(stats, "visibility");
    DeepBuffer frame;
    frame.x0 = frame.y0 = 0, frame.width = scene.camera.width, frame.height = scene.camera.height;
    return render_visibility(scene, accel, stats, sink, grow(crop, margin, frame));
}

/// Loads the request's cache file; with a crop and --regather, the records seen inside the
/// crop are left out (they are gathered again).
LoadedCache load_request_cache(const Scene& scene, const RenderRequest& request, IrradianceCache& cache) {
    LoadedCache loaded;
    if (request.cache_in.empty() || (request.regather && !scene.render.visibility.has_crop())) return loaded;
    std::function<bool(const Record&)> keep;
    if (request.regather) {
        const auto crop = scene.render.visibility.crop;
        keep = [crop, camera = CameraRays(scene.camera)](const Record& r) { return !camera.projects_into(r.p, crop); };
    }
    return load_cache(request.cache_in, scene, request.force, request.cache_reuse, cache, keep);
}

void set_metadata(Image& image, const Scene& scene, const DeepBuffer& deep, Stats& stats) {
    auto& md = image.metadata;
    md["scene"] = scene.path;
    const nlohmann::json params = param_values(scene, ~0u);
    for (const auto& [key, value] : params.items()) md[key] = value.is_string() ? value.get<std::string>() : value.dump();
    md["deep_seed"] = std::to_string(deep.seed);
    md["deep_spp"] = std::to_string(deep.spp);
    md["scene_fingerprint"] = fmt::format("{:016x}", deep.scene_fingerprint);
    md["render_time_s"] = fmt::format("{:.3f}", stats.to_json()["total_s"].get<double>());
}

/// The fragments of every `step`-th window pixel in x and y; the other pixels empty.
DeepBuffer lattice_of(const DeepBuffer& deep, int step) {
    DeepBuffer out = deep;
    out.fragments.clear();
    out.offsets.assign(deep.pixel_count() + 1, 0);
    for (int wy = 0; wy < deep.height; ++wy)
        for (int wx = 0; wx < deep.width; ++wx) {
            const size_t i = static_cast<size_t>(wy) * deep.width + wx;
            if (wx % step == 0 && wy % step == 0) {
                auto f = deep.pixel(wx, wy);
                out.fragments.insert(out.fragments.end(), f.begin(), f.end());
            }
            out.offsets[i + 1] = static_cast<uint32_t>(out.fragments.size());
        }
    return out;
}

/// Each pixel of every layer takes the value of its step x step block's first pixel.
void fill_blocks(Image& img, int step) {
    for (Layer& l : img.layers) {
        const size_t nc = l.channels.size();
        for (int y = 0; y < img.height; ++y)
            for (int x = 0; x < img.width; ++x) {
                const float* src = img.at(l, x - x % step, y - y % step);
                std::copy_n(src, nc, img.at(l, x, y));
            }
    }
}

}  // namespace

Image paste_over(const Image& base, const Image& window, const std::string& base_name) {
    if (base.full_width != window.full_width || base.full_height != window.full_height || base.x0 != 0 || base.y0 != 0 ||
        base.width != base.full_width || base.height != base.full_height)
        throw InputError(base_name, "", fmt::format("base image is {}x{} (window {}x{} at {},{}); the render is a {}x{} frame",
                                                    base.full_width, base.full_height, base.width, base.height, base.x0,
                                                    base.y0, window.full_width, window.full_height));
    Image out = base;
    out.metadata = window.metadata;
    for (const Layer& l : window.layers) {
        Layer* dst = out.find(l.name);
        if (!dst || dst->channels != l.channels)
            throw InputError(base_name, l.name, "base image lacks this layer (render it with the same settings)");
        const size_t nc = l.channels.size();
        for (int y = 0; y < window.height; ++y)
            std::copy_n(&l.data[static_cast<size_t>(y) * window.width * nc], static_cast<size_t>(window.width) * nc,
                        &dst->data[((static_cast<size_t>(y + window.y0)) * out.width + window.x0) * nc]);
    }
    return out;
}

RenderResult render(const Scene& scene, const RenderRequest& request, Stats& stats, ProgressSink* progress) {
    if (double need = estimate_render_bytes(scene), have = available_bytes(); need > 0.8 * have)
        throw InputError(scene.path, "camera.resolution",
                         fmt::format("a {}x{} frame needs about {:.1f} GiB; {:.1f} GiB are available (render a crop)",
                                     scene.camera.width, scene.camera.height, need / 1073741824.0, have / 1073741824.0));
    const int threads = scene.render.parallel.threads > 0 ? scene.render.parallel.threads : tbb::this_task_arena::max_concurrency();
    tbb::task_arena arena(threads);
    stats.set("threads", threads);
    report_dicing(scene, stats);
    CancellableSink sink(progress, request.cancel);
    ProgressSink* const ps = progress || request.cancel ? &sink : nullptr;
    RenderResult result;
    const IndirectSettings& ind = scene.render.indirect;
    arena.execute([&] {
        std::unique_ptr<SceneAccel> accel;
        {
            PhaseTimer t(stats, "build BVH");
            accel = std::make_unique<SceneAccel>(scene);
        }
        stats.set("ray_offset", accel->ray_offset());
        DeepBuffer gathered = gathered_window(scene, request, *accel, stats, ps);
        if (!request.deep_out.empty()) {
            PhaseTimer t(stats, "write deep");
            write_deep(request.deep_out, gathered);
        }
        result.deep = scene.render.visibility.has_crop() ? sub_window(gathered, frame_window(scene)) : gathered;
        Materials materials(scene);
        DirectLighting lighting(scene, *accel);
        std::vector<Indirect> indirect;
        std::unique_ptr<RadiosityTextures> radiosity;
        std::vector<uint8_t> refined;
        size_t baked_before = 0;  // radiosity sides held before this render
        const bool in_memory = request.shade_only && request.shade_cache && ind.gi == GiMode::Cache;
        if (in_memory) {
            result.records_loaded = request.shade_cache->size();
        } else if (ind.gi == GiMode::Cache || !request.cache_in.empty()) {
            result.cache = std::make_unique<IrradianceCache>(scene.bounds(), scene.render.cache, ind.ao);
            PhaseTimer tl(stats, "cache read");
            LoadedCache loaded = load_request_cache(scene, request, *result.cache);
            result.records_loaded = loaded.records;
            if (!loaded.differences.empty()) stats.set("cache_reused_with_other_settings", nlohmann::json(loaded.differences));
        }
        result.cache_info = cache_file_info(scene, request.frame);
        const IrradianceCache* const shaded = in_memory ? request.shade_cache.get() : result.cache.get();
        // A shading-only re-shade of a loaded cache skips the gathering and refinement passes.
        const bool gathering = !(ind.gi == GiMode::Cache && request.shade_only && (in_memory || !request.cache_in.empty()));
        if (ind.any() && gathering) {
            GatherSettings gs = gather_settings(scene);
            gs.record_terms = ind.gi == GiMode::Cache;  // brute force needs no gradients
            gs.hessian = gs.record_terms && scene.render.cache.metric == Metric::Hessian;
            gs.cancel = request.cancel;
            if (scene.render.radiosity.enabled && !gs.ao) radiosity = radiosity_for(scene, materials, lighting, stats, ps);
            baked_before = radiosity ? radiosity->baked_sides() : 0;
            Gatherer gatherer(scene, *accel, materials, lighting, radiosity.get(), gs);
            uint64_t rays_before = stats.total().gather_rays;
            PhaseTimer t(stats, "gather");
            if (ind.gi == GiMode::Cache) {
                IrradianceCache& cache = *result.cache;
                SubPassCallback after;
                std::vector<Color> direct;
                std::vector<uint8_t> visited;
                if (scene.render.parallel.preview && request.preview) {
                    direct = fragment_direct_radiance(scene, result.deep, materials, lighting, false, stats);
                    visited.assign(result.deep.pixel_count(), 0);
                    after = [&](const SubPass& sp, size_t, size_t) {
                        const DeepBuffer& d = result.deep;
                        for (int wy = 0; wy < d.height; ++wy)
                            for (int wx = 0; wx < d.width; ++wx)
                                if (sp.contains(wx + d.x0, wy + d.y0)) visited[static_cast<size_t>(wy) * d.width + wx] = 1;
                        std::vector<Indirect> pre = preview_indirect(scene, d, cache, visited, sp.step);
                        request.preview(shade(scene, d, materials, lighting, &pre, stats, nullptr, &direct));
                    };
                }
                std::unique_ptr<Gatherer> first;
                if (scene.render.cache.min_rays > 0 && scene.render.cache.min_rays < gs.rays) {
                    GatherSettings fs = gs;
                    fs.rays = scene.render.cache.min_rays;
                    first = std::make_unique<Gatherer>(scene, *accel, materials, lighting, radiosity.get(), fs);
                }
                gathering_pass(scene, gathered, gatherer, cache, stats, ps, after, request.frame, first.get());
                if (refinement_runs(scene)) {
                    // A refined fragment's gather feeds that fragment only: no gradients needed.
                    GatherSettings own = gs;
                    own.record_terms = own.hessian = false;
                    if (scene.render.cache.refine_rays > 0) own.rays = scene.render.cache.refine_rays;
                    Gatherer refiner(scene, *accel, materials, lighting, radiosity.get(), own);
                    // Over the frame's window only: the margin's fragments are never shaded.
                    if (refinement_pass(scene, result.deep, refiner, cache, stats, ps, request.frame) > 0 && after) {
                        const auto schedule = subpass_schedule(1);
                        after(schedule.back(), schedule.size() - 1, schedule.size());
                    }
                }
                result.records_new = cache.size() - result.records_loaded;
                stats.set("records_loaded", static_cast<double>(result.records_loaded));
                stats.set("records_new", static_cast<double>(result.records_new));
            } else {
                indirect = gather_every_fragment(scene, result.deep, gatherer, stats, ps);
                stats.set("gathers", static_cast<double>(result.deep.fragments.size()));
                stats.set("rays_per_gather", gatherer.grid().rays());
            }
            double secs = t.stop();
            uint64_t rays = stats.total().gather_rays - rays_before;
            stats.set("gather_rays_per_s", secs > 0 ? static_cast<double>(rays) / secs : 0.0);
        }
        if (!gathering && shaded) {
            stats.set("records", static_cast<double>(shaded->size()));
            stats.set("records_loaded", static_cast<double>(result.records_loaded));
            stats.set("records_new", 0.0);
        }
        {
            PhaseTimer t(stats, "shading");
            if (!gathering && shaded && scene.render.parallel.preview && request.preview) {
                // A re-shade's quick look first: one pixel in 16 shaded exactly as the final
                // image shades it, standing for its 4x4 block.
                const DeepBuffer coarse = lattice_of(result.deep, 4);
                const std::vector<Indirect> light = shading_pass(scene, coarse, *shaded, stats, nullptr);
                Image look = shade(scene, coarse, materials, lighting, &light, stats, nullptr);
                fill_blocks(look, 4);
                request.preview(look);
            }
            if (ind.gi == GiMode::Cache) {
                auto t0 = std::chrono::steady_clock::now();
                indirect = shading_pass(scene, result.deep, *shaded, stats, ps, &refined);
                stats.set("interpolation_s", std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
            }
            result.image = shade(scene, result.deep, materials, lighting, ind.any() ? &indirect : nullptr, stats, ps);
        }
        if (shaded) {
            std::vector<Vec3> positions;
            for (size_t i = 0; i < shaded->size(); ++i) positions.push_back(shaded->record(i).p);
            add_records_layer(result.image, scene.camera, positions);
        }
        // After the shading pass: refined fragments' gathers may have baked sides too.
        if (radiosity) save_radiosity(*radiosity, baked_before, scene, stats);
        if (shaded && (refinement_runs(scene) || shaded->fragment_record_count() > 0))
            add_fragment_mask_layer(result.image, result.deep, refined, "refined");
    });
    stats.set("pixels", static_cast<double>(result.deep.pixel_count()));
    if (result.deep.pixel_count() > 0)
        stats.set("gather_rays_per_pixel", static_cast<double>(stats.total().gather_rays) /
                                               static_cast<double>(result.deep.pixel_count()));
    set_metadata(result.image, scene, result.deep, stats);
    return result;
}

}  // namespace bounce
