#include "bounce/render/frame_passes.h"

#include <fmt/format.h>

#include <chrono>
#include <cstdio>
#include <cstring>

#include "bounce/cache/control_variate.h"
#include "bounce/cache/passes.h"
#include "bounce/cache/temporal_redo.h"
#include "bounce/core/error.h"
#include "bounce/gather/gather.h"
#include "bounce/render/distributed.h"
#include "bounce/render/render.h"
#include "bounce/shade/layers.h"
#include "bounce/shade/shade.h"

namespace bounce {

namespace {

/// Frames of a shot: a point where a kept record weighs this much is covered by it alone (its
/// centre moved a little in the image since the frame that made it). Measured on shot A.
constexpr float kTemporalOwnWeight = 0.9f;

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
            if (ctx.comm.size() == 1) {
                out.gathered = render_visibility(scene, ctx.accel, ctx.stats, ctx.progress, plan.gather_window);
                break;
            }
            // Each process keeps the fragments of its own tiles, unless a crop's tiles differ
            // from the gathered window's or rank 0 writes the deep file.
            out.gathered = visibility_in_tiles(ctx.comm, scene, ctx.accel, ctx.stats, plan.gather_window,
                                               cropped || !plan.deep_out.empty());
            break;
        }
    }
    if (cropped) out.crop = sub_window(out.gathered, plan.window);
    return out;
}

std::unique_ptr<IrradianceCache> copy_cache(const IrradianceCache& from, const Scene& scene) {
    if (from.made_like(scene.bounds(), from.settings(), from.ao_only())) return from.clone();
    auto cache = std::make_unique<IrradianceCache>(scene.bounds(), from.settings(), from.ao_only());
    cache->set_luminance_floor(from.luminance_floor());
    cache->set_light_scales(from.light_scales());
    for (size_t i = 0; i < from.size(); ++i) cache->insert_loaded(from.record(i));
    for (size_t i = 0; i < from.fragment_record_count(); ++i) cache->insert_fragment_record(from.fragment_record_at(i));
    return cache;
}

CacheStartResult cache_start_pass(const FrameContext& ctx, const FramePlan& plan, const FrameState& previous,
                                  const RadiosityResult& radiosity) {
    const Scene& scene = ctx.scene;
    CacheStartResult out;
    if (plan.cache == CacheStart::None) return out;
    PhaseTimer t(ctx.stats, "cache read");
    out.cache = std::make_unique<IrradianceCache>(scene.bounds(), scene.render.cache, scene.render.indirect.ao);
    if (scene.render.cache.light_parts) out.cache->set_light_scales(light_scales(scene));
    if (plan.cache == CacheStart::Temporal) {
        // The previous frame's records and those still waiting from before, judged for this frame.
        out.judged = judge_records(*previous.cache, previous.waiting, previous.gathers, *previous.scene, scene, *plan.changes, radiosity.changed,
                                   radiosity.brightest);
        out.cache->set_luminance_floor(previous.cache->luminance_floor());
        for (const Record& r : out.judged.valid) out.cache->insert_loaded(r);
        for (const Record& r : out.judged.fragment_valid) out.cache->insert_fragment_record(r);
        out.records_loaded = out.judged.valid.size();
        return out;
    }
    std::function<bool(const Record&)> keep;
    if (plan.flush_crop)
        keep = [crop = plan.window, camera = CameraRays(scene.camera)](const Record& r) { return !camera.projects_into(r.p, crop); };
    if (plan.cache == CacheStart::Previous) {
        const IrradianceCache& from = *previous.cache;
        // Records that keep their light parts show today's light colours and intensities: the
        // bounce light of a light edit, exactly (docs/lighting-tool.md).
        std::vector<Color> scales = out.cache->light_scales();
        if (!keep && from.made_like(scene.bounds(), scene.render.cache, scene.render.indirect.ao)) {
            out.cache = from.clone();  // the index inserting every record again would build
        } else {
            out.cache->set_luminance_floor(from.luminance_floor());
            for (size_t i = 0; i < from.size(); ++i)
                if (!keep || keep(from.record(i))) out.cache->insert_loaded(from.record(i));
            for (size_t i = 0; i < from.fragment_record_count(); ++i)
                if (!keep || keep(from.fragment_record_at(i))) out.cache->insert_fragment_record(from.fragment_record_at(i));
        }
        out.cache->rescale_lights(std::move(scales));
        out.records_loaded = out.cache->size();
        return out;
    }
    if (plan.cache == CacheStart::File) {
        LoadedCache loaded = load_cache(plan.cache_in, scene, plan.force, plan.cache_reuse, *out.cache, keep);
        out.records_loaded = loaded.records;
        out.differences = loaded.differences;
        out.other_lighting = loaded.other_lighting;
    }
    return out;
}

namespace {

/// What the redoing of a shot's earlier records needs to know of this frame.
TemporalFrame temporal_frame(const FrameContext& ctx, const FramePlan& plan) {
    return {ctx.scene, plan.changes.get(), plan.frame, plan.keep_hits};
}

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
                                   const RadiosityTextures* radiosity, IrradianceCache& cache, TemporalJudgement judged,
                                   const std::function<void(const Image&)>& preview, const SpecularSitesResult& specular) {
    const Scene& scene = ctx.scene;
    const GatherSettings gs = frame_gather_settings(ctx, true);
    Gatherer gatherer(scene, ctx.accel, ctx.materials, ctx.lighting, radiosity, gs);
    GatherPassResult out;
    const size_t before = cache.size();
    GatheringOptions options;
    options.frame = plan.frame;
    options.keep_hits = plan.keep_hits;
    options.comm = &ctx.comm;
    // The weight sum that covers a point stays the settings' (1.5): asking only 1 of kept
    // records saved 9 % of shot A's rays for 0.15 points more error and 7 % more flicker
    // (docs/animation.md).
    if (plan.cache == CacheStart::Temporal) options.own_weight = kTemporalOwnWeight;
    if (plan.preview && preview) options.after_subpass = preview_after_subpass(ctx, deep.shaded(), cache, preview);
    std::unique_ptr<Gatherer> first;
    if (scene.render.cache.min_rays > 0 && scene.render.cache.min_rays < gs.rays) {
        GatherSettings fs = gs;
        fs.rays = scene.render.cache.min_rays;
        first = std::make_unique<Gatherer>(scene, ctx.accel, ctx.materials, ctx.lighting, radiosity, fs);
        options.first = first.get();
    }
    std::unique_ptr<StaleRecords> stale;
    if (!judged.stale.empty()) {
        stale = std::make_unique<StaleRecords>(std::move(judged.stale), std::move(judged.why), scene.bounds(), cache.settings(),
                                               cache.ao_only(), redo_function(temporal_frame(ctx, plan), cache, gatherer));
        options.stale = stale.get();
    }
    gathering_pass(scene, deep.gathered, gatherer, cache, ctx.stats, ctx.progress, options);
    if (stale) {
        out.regathered = stale->regathered, out.reshaded = stale->reshaded;
        out.waiting = stale->waiting();
    }
    if (plan.refine) {
        // A refined fragment's gather feeds that fragment only: no gradients needed.
        GatherSettings own = gs;
        own.record_terms = own.hessian = false;
        if (scene.render.cache.refine_rays > 0) own.rays = scene.render.cache.refine_rays;
        Gatherer refiner(scene, ctx.accel, ctx.materials, ctx.lighting, radiosity, own);
        // Over the frame's window only: the margin's fragments are never shaded.
        RefinementOptions ro;
        ro.frame = plan.frame;
        ro.keep_hits = plan.keep_hits || plan.keep_gathers;  // the next frames reuse refinement's rays
        ro.comm = &ctx.comm;
        if (!judged.fragment_stale.empty()) {
            ro.stale = &judged.fragment_stale;
            ro.update = fragment_update_function(temporal_frame(ctx, plan), refiner, cache);
        }
        std::unique_ptr<EarlierGathers> earlier;
        if (plan.keep_gathers) {
            earlier = std::make_unique<EarlierGathers>(std::move(judged.earlier_gathers), scene.bounds(),
                                                       scene.render.cache.temporal_refine_reuse);
            ro.earlier = earlier.get();
        }
        std::unique_ptr<EarlierGathers> refined_before;
        if (plan.cache == CacheStart::Temporal && plan.changes && plan.changes->camera) {
            refined_before = refined_the_frame_before(cache, judged, scene, plan.frame);
            ro.refined_before = refined_before.get();
        }
        out.fragment_records_new = refinement_pass(scene, deep.shaded(), refiner, cache, ctx.stats, ctx.progress, ro);
        if (earlier) out.gathers = gathers_to_keep(*earlier, cache, plan.frame);
        if (out.fragment_records_new > 0 && options.after_subpass) {
            const auto schedule = subpass_schedule(1);
            options.after_subpass(schedule.back(), schedule.size() - 1, schedule.size());
        }
    }
    out.site_records_new = specular_gather_pass(ctx, plan, specular.sites, gatherer, cache);
    out.records_new = cache.size() - before - out.regathered - out.reshaded;  // made this frame
    return out;
}

std::vector<Indirect> brute_gather_pass(const FrameContext& ctx, const DeepBuffer& deep, const RadiosityTextures* radiosity,
                                        SpecularSitesResult& specular) {
    Gatherer gatherer(ctx.scene, ctx.accel, ctx.materials, ctx.lighting, radiosity, frame_gather_settings(ctx, false));
    std::vector<Indirect> light =
        ctx.comm.size() == 1 ? gather_every_fragment(ctx.scene, deep, gatherer, ctx.stats, ctx.progress)
                             : indirect_in_tiles(ctx.comm, deep, ctx.scene.render.parallel.tile_size, [&](const DeepBuffer& tile) {
                                   return gather_every_fragment(ctx.scene, tile, gatherer, ctx.stats, nullptr);
                               });
    specular_brute_pass(ctx, gatherer, specular);
    ctx.stats.set("gathers", static_cast<double>(deep.fragments.size() + specular.brute.size()));
    ctx.stats.set("rays_per_gather", gatherer.grid().rays());
    return light;
}

namespace {

ShadeResult shade_window(const FrameContext& ctx, const DeepBuffer& deep, const IrradianceCache* cache,
                         const std::vector<Indirect>* brute, const SpecularSitesResult& specular,
                         const RadiosityTextures* radiosity, ProgressSink* progress) {
    const Scene& scene = ctx.scene;
    ShadeResult out;
    const SiteLightResult sites = site_light_for(ctx, specular, window_of(deep), cache, radiosity);
    std::vector<Indirect> interpolated;
    LightShares shares;
    if (cache && scene.render.indirect.gi == GiMode::Cache) {
        auto t0 = std::chrono::steady_clock::now();
        // Per-light indirect layers: each light's share of the records' light parts.
        const bool per_light = scene.render.shading.layers == LayerSet::Components && !scene.render.indirect.ao &&
                               !scene.lights.empty() && cache->has_light_parts(scene.lights.size());
        InterpolatedLight light = interpolation_pass(scene, deep, *cache, ctx.stats, progress, true, per_light);
        ctx.stats.set("interpolation_s", std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
        interpolated = std::move(light.light);
        shares = std::move(light.shares);
        if (scene.render.cache.correction_rays > 0) {  // records as a control variate (FramePlan::correct)
            PhaseTimer timer(ctx.stats, "correction");
            GatherSettings gs = frame_gather_settings(ctx, false);
            gs.rays = scene.render.cache.correction_rays;
            const Gatherer gatherer(scene, ctx.accel, ctx.materials, ctx.lighting, radiosity, gs);
            correction_pass(scene, deep, *cache, gatherer, interpolated, ctx.stats, progress);
        }
        out.refined = fragment_mask(deep, light.refined);
        out.shading_misses = light.misses + sites.misses;
        if (specular.any()) ctx.stats.set("shading_misses", static_cast<double>(out.shading_misses));
        brute = &interpolated;
    }
    out.image = shade(scene, deep, ctx.materials, ctx.lighting, scene.render.indirect.any() ? brute : nullptr, ctx.stats,
                      progress, nullptr, sites.view(), scene.render.shading.deep_colour ? &out.colours : nullptr,
                      shares.lights > 0 ? &shares : nullptr);
    return out;
}

/// Each process shades its tiles; rank 0 takes the whole image (the others' stays empty).
ShadeResult shade_in_tiles(const FrameContext& ctx, const DeepBuffer& deep, const IrradianceCache* cache,
                           const std::vector<Indirect>* brute, const SpecularSitesResult& specular,
                           const RadiosityTextures* radiosity) {
    const auto tiles = in_tiles(ctx.comm, window_of(deep), ctx.scene.render.parallel.tile_size, TilesTo::First,
                                [&](const std::array<int, 4>& w) {
        const DeepBuffer sub = sub_window(deep, w);
        const std::vector<Indirect> light = brute ? window_slice(deep, *brute, w) : std::vector<Indirect>();
        ShadeResult r = shade_window(ctx, sub, cache, brute ? &light : nullptr, specular, radiosity, nullptr);
        // The refined mask travels as a layer of the tile's image.
        if (!r.refined.empty()) add_mask_layer(r.image, r.refined, "refined");
        const uint64_t misses = r.shading_misses;
        return std::string(reinterpret_cast<const char*>(&misses), sizeof(misses)) + serialize_image(r.image);
    });
    ShadeResult out;
    if (ctx.comm.rank() != 0) return out;  // rank 0 writes the image
    std::vector<Image> images;
    for (const std::string& b : tiles) {
        uint64_t misses = 0;
        std::memcpy(&misses, b.data(), sizeof(misses));
        out.shading_misses += misses;
        images.push_back(parse_image(b.substr(sizeof(misses))));
    }
    out.image = assemble_tiles(window_of(deep), images);
    if (Layer* mask = out.image.find("refined")) {
        out.refined = std::move(mask->data);
        out.image.layers.pop_back();  // added back where one process adds it
    }
    ctx.stats.set("shading_misses", static_cast<double>(out.shading_misses));
    return out;
}

}  // namespace

ShadeResult shading_pass(const FrameContext& ctx, const DeepBuffer& deep, const IrradianceCache* cache,
                         const std::vector<Indirect>* brute, const SpecularSitesResult& specular,
                         const RadiosityTextures* radiosity, const std::function<void(const Image&)>& quick_look) {
    const Scene& scene = ctx.scene;
    PhaseTimer t(ctx.stats, "shading");
    if (cache && quick_look) {
        // A re-shade's quick look first: one pixel in 16 shaded exactly as the final image
        // shades it, standing for its 4x4 block.
        const DeepBuffer coarse = lattice_of(deep, 4);
        const InterpolatedLight light = interpolation_pass(scene, coarse, *cache, ctx.stats, nullptr);
        Image look = shade(scene, coarse, ctx.materials, ctx.lighting, &light.light, ctx.stats, nullptr);
        fill_blocks(look, 4);
        quick_look(look);
    }
    if (ctx.comm.size() > 1) return shade_in_tiles(ctx, deep, cache, brute, specular, radiosity);
    return shade_window(ctx, deep, cache, brute, specular, radiosity, ctx.progress);
}

}  // namespace bounce
