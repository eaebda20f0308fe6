#include "bounce/render/frame_passes.h"

#include <fmt/format.h>

#include <chrono>
#include <cstdio>

#include "bounce/cache/passes.h"
#include "bounce/core/error.h"
#include "bounce/gather/gather.h"
#include "bounce/render/render.h"
#include "bounce/shade/layers.h"
#include "bounce/shade/shade.h"

namespace bounce {

namespace {

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

/// The window of `deep` the plan gathers in, checked against what the deep buffer covers.
DeepBuffer window_of(const DeepBuffer& deep, const FramePlan& plan, const std::string& origin, bool cropped) {
    // Without a crop, a deep file of a window renders that window.
    if (!cropped) return deep;
    const auto& c = plan.window;
    if (c[0] < deep.x0 || c[2] < deep.y0 || c[1] > deep.x0 + deep.width || c[3] > deep.y0 + deep.height)
        throw InputError(origin, "", fmt::format("the deep file covers pixels [{}, {}) x [{}, {}), not the crop", deep.x0,
                                                 deep.x0 + deep.width, deep.y0, deep.y0 + deep.height));
    const auto& g = plan.gather_window;
    return sub_window(deep, {std::max(deep.x0, g[0]), std::min(deep.x0 + deep.width, g[1]), std::max(deep.y0, g[2]),
                             std::min(deep.y0 + deep.height, g[3])});
}

}  // namespace

VisibilityResult visibility_pass(const FrameContext& ctx, const FramePlan& plan, const FrameState& previous) {
    const Scene& scene = ctx.scene;
    const bool cropped = scene.render.visibility.has_crop();
    VisibilityResult out;
    switch (plan.visibility) {
        case VisibilityStep::Previous:
            validate_deep_for_scene(*previous.deep, scene, "the session's deep buffer");
            out.gathered = window_of(*previous.deep, plan, "the session's deep buffer", cropped);
            break;
        case VisibilityStep::ReadFile: {
            DeepBuffer deep;
            {
                PhaseTimer t(ctx.stats, "read deep");
                deep = read_deep(plan.deep_in);
            }
            validate_deep_for_scene(deep, scene, plan.deep_in);
            out.gathered = window_of(deep, plan, plan.deep_in, cropped);
            break;
        }
        case VisibilityStep::Trace: {
            check_camera_sees_geometry(scene, ctx.accel);
            PhaseTimer t(ctx.stats, "visibility");
            out.gathered = render_visibility(scene, ctx.accel, ctx.stats, ctx.progress, plan.gather_window);
            break;
        }
    }
    out.shaded = cropped ? sub_window(out.gathered, plan.window) : out.gathered;
    return out;
}

std::unique_ptr<IrradianceCache> copy_cache(const IrradianceCache& from, const Scene& scene) {
    auto cache = std::make_unique<IrradianceCache>(scene.bounds(), from.settings(), from.ao_only());
    cache->set_luminance_floor(from.luminance_floor());
    for (size_t i = 0; i < from.size(); ++i) cache->insert_loaded(from.record(i));
    for (size_t i = 0; i < from.fragment_record_count(); ++i) cache->insert_fragment_record(from.fragment_record_at(i));
    return cache;
}

CacheStartResult cache_start_pass(const FrameContext& ctx, const FramePlan& plan, const FrameState& previous) {
    const Scene& scene = ctx.scene;
    CacheStartResult out;
    if (plan.cache == CacheStart::None) return out;
    PhaseTimer t(ctx.stats, "cache read");
    std::function<bool(const Record&)> keep;
    if (plan.flush_crop)
        keep = [crop = plan.window, camera = CameraRays(scene.camera)](const Record& r) { return !camera.projects_into(r.p, crop); };
    if (plan.cache == CacheStart::Previous) {
        out.cache = std::make_unique<IrradianceCache>(scene.bounds(), scene.render.cache, scene.render.indirect.ao);
        const IrradianceCache& from = *previous.cache;
        out.cache->set_luminance_floor(from.luminance_floor());
        for (size_t i = 0; i < from.size(); ++i)
            if (!keep || keep(from.record(i))) out.cache->insert_loaded(from.record(i)), ++out.records_loaded;
        for (size_t i = 0; i < from.fragment_record_count(); ++i)
            if (!keep || keep(from.fragment_record_at(i))) out.cache->insert_fragment_record(from.fragment_record_at(i));
        return out;
    }
    out.cache = std::make_unique<IrradianceCache>(scene.bounds(), scene.render.cache, scene.render.indirect.ao);
    if (plan.cache == CacheStart::File) {
        LoadedCache loaded = load_cache(plan.cache_in, scene, plan.force, plan.cache_reuse, *out.cache, keep);
        out.records_loaded = loaded.records;
        out.differences = loaded.differences;
    }
    return out;
}

std::unique_ptr<RadiosityTextures> radiosity_pass(const FrameContext& ctx, const FramePlan& plan) {
    if (plan.radiosity == RadiosityStep::None) return nullptr;
    const RadiositySettings& settings = ctx.scene.render.radiosity;
    auto rt = std::make_unique<RadiosityTextures>();
    if (plan.radiosity == RadiosityStep::Load) {
        PhaseTimer t(ctx.stats, "radiosity load");
        std::string why;
        if (RadiosityTextures::load(settings.folder, ctx.scene, settings, ctx.materials, ctx.lighting, *rt, why)) {
            ctx.stats.set("radiosity_reused", 1);
            return rt;
        }
        if (ctx.progress)
            std::fprintf(stderr, "radiosity textures in %s not reused: %s; baking\n", settings.folder.c_str(), why.c_str());
    }
    *rt = RadiosityTextures::lazy(ctx.scene, ctx.materials, ctx.lighting, settings);
    ctx.stats.set("radiosity_reused", 0);
    return rt;
}

void save_radiosity_pass(const FrameContext& ctx, const RadiosityTextures& rt, size_t baked_before) {
    const size_t baked = rt.baked_sides();
    ctx.stats.set("radiosity_sides_baked", static_cast<double>(baked - baked_before));
    ctx.stats.set("radiosity_sides", static_cast<double>(rt.sides()));
    const std::string& folder = ctx.scene.render.radiosity.folder;
    if (folder.empty() || baked == baked_before) return;
    PhaseTimer t(ctx.stats, "radiosity save");
    rt.save(folder);
}

namespace {

GatherSettings frame_gather_settings(const FrameContext& ctx, bool record_terms) {
    GatherSettings gs = gather_settings(ctx.scene);
    gs.record_terms = record_terms;  // brute force needs no gradients
    gs.hessian = record_terms && ctx.scene.render.cache.metric == Metric::Hessian;
    gs.cancel = ctx.cancel;
    return gs;
}

/// The preview callback of the gathering pass: after each sub-pass, the image with every
/// visited pixel's interpolation standing for the pixels around it.
SubPassCallback preview_after_subpass(const FrameContext& ctx, const DeepBuffer& deep, const IrradianceCache& cache,
                                      const std::function<void(const Image&)>& preview) {
    auto direct = std::make_shared<std::vector<Color>>(
        fragment_direct_radiance(ctx.scene, deep, ctx.materials, ctx.lighting, false, ctx.stats));
    auto visited = std::make_shared<std::vector<uint8_t>>(deep.pixel_count(), 0);
    return [&ctx, &deep, &cache, preview, direct, visited](const SubPass& sp, size_t, size_t) {
        for (int wy = 0; wy < deep.height; ++wy)
            for (int wx = 0; wx < deep.width; ++wx)
                if (sp.contains(wx + deep.x0, wy + deep.y0)) (*visited)[static_cast<size_t>(wy) * deep.width + wx] = 1;
        std::vector<Indirect> pre = preview_indirect(ctx.scene, deep, cache, *visited, sp.step);
        preview(shade(ctx.scene, deep, ctx.materials, ctx.lighting, &pre, ctx.stats, nullptr, direct.get()));
    };
}

}  // namespace

GatherPassResult cache_gather_pass(const FrameContext& ctx, const FramePlan& plan, const VisibilityResult& deep,
                                   const RadiosityTextures* radiosity, IrradianceCache& cache,
                                   const std::function<void(const Image&)>& preview) {
    const Scene& scene = ctx.scene;
    const GatherSettings gs = frame_gather_settings(ctx, true);
    Gatherer gatherer(scene, ctx.accel, ctx.materials, ctx.lighting, radiosity, gs);
    GatherPassResult out;
    const size_t before = cache.size();
    SubPassCallback after;
    if (plan.preview && preview) after = preview_after_subpass(ctx, deep.shaded, cache, preview);
    std::unique_ptr<Gatherer> first;
    if (scene.render.cache.min_rays > 0 && scene.render.cache.min_rays < gs.rays) {
        GatherSettings fs = gs;
        fs.rays = scene.render.cache.min_rays;
        first = std::make_unique<Gatherer>(scene, ctx.accel, ctx.materials, ctx.lighting, radiosity, fs);
    }
    gathering_pass(scene, deep.gathered, gatherer, cache, ctx.stats, ctx.progress, after, plan.frame, first.get());
    if (plan.refine) {
        // A refined fragment's gather feeds that fragment only: no gradients needed.
        GatherSettings own = gs;
        own.record_terms = own.hessian = false;
        if (scene.render.cache.refine_rays > 0) own.rays = scene.render.cache.refine_rays;
        Gatherer refiner(scene, ctx.accel, ctx.materials, ctx.lighting, radiosity, own);
        // Over the frame's window only: the margin's fragments are never shaded.
        out.fragment_records_new = refinement_pass(scene, deep.shaded, refiner, cache, ctx.stats, ctx.progress, plan.frame);
        if (out.fragment_records_new > 0 && after) {
            const auto schedule = subpass_schedule(1);
            after(schedule.back(), schedule.size() - 1, schedule.size());
        }
    }
    out.records_new = cache.size() - before;
    return out;
}

std::vector<Indirect> brute_gather_pass(const FrameContext& ctx, const DeepBuffer& deep, const RadiosityTextures* radiosity) {
    Gatherer gatherer(ctx.scene, ctx.accel, ctx.materials, ctx.lighting, radiosity, frame_gather_settings(ctx, false));
    std::vector<Indirect> light = gather_every_fragment(ctx.scene, deep, gatherer, ctx.stats, ctx.progress);
    ctx.stats.set("gathers", static_cast<double>(deep.fragments.size()));
    ctx.stats.set("rays_per_gather", gatherer.grid().rays());
    return light;
}

ShadeResult shading_pass(const FrameContext& ctx, const DeepBuffer& deep, const IrradianceCache* cache,
                         const std::vector<Indirect>* brute, const std::function<void(const Image&)>& quick_look) {
    const Scene& scene = ctx.scene;
    PhaseTimer t(ctx.stats, "shading");
    ShadeResult out;
    if (cache && quick_look) {
        // A re-shade's quick look first: one pixel in 16 shaded exactly as the final image
        // shades it, standing for its 4x4 block.
        const DeepBuffer coarse = lattice_of(deep, 4);
        const InterpolatedLight light = interpolation_pass(scene, coarse, *cache, ctx.stats, nullptr);
        Image look = shade(scene, coarse, ctx.materials, ctx.lighting, &light.light, ctx.stats, nullptr);
        fill_blocks(look, 4);
        quick_look(look);
    }
    std::vector<Indirect> interpolated;
    if (cache && scene.render.indirect.gi == GiMode::Cache) {
        auto t0 = std::chrono::steady_clock::now();
        InterpolatedLight light = interpolation_pass(scene, deep, *cache, ctx.stats, ctx.progress);
        ctx.stats.set("interpolation_s", std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
        interpolated = std::move(light.light);
        out.refined = std::move(light.refined);
        out.shading_misses = light.misses;
        brute = &interpolated;
    }
    out.image = shade(scene, deep, ctx.materials, ctx.lighting, scene.render.indirect.any() ? brute : nullptr, ctx.stats,
                      ctx.progress);
    return out;
}

}  // namespace bounce
