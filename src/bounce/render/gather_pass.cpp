// The gathering pass: records where fragments need them (earlier frames' stale records redone
// where they are needed), refinement, the sites of mirrors and glass; or brute force's gather
// at every fragment.
#include "bounce/render/frame_passes.h"

#include "bounce/cache/passes.h"
#include "bounce/cache/temporal_redo.h"
#include "bounce/gather/gather.h"
#include "bounce/render/distributed.h"
#include "bounce/shade/shade.h"

namespace bounce {

namespace {

/// Frames of a shot: a point where a kept record weighs this much is covered by it alone (its
/// centre moved a little in the image since the frame that made it). Measured on shot A.
constexpr float kTemporalOwnWeight = 0.9f;

/// What the redoing of a shot's earlier records needs to know of this frame.
TemporalFrame temporal_frame(const FrameContext& ctx, const FramePlan& plan) {
    return {ctx.scene, plan.changes.get(), plan.frame, plan.keep_hits};
}

/// The preview callback of the gathering pass: after each sub-pass, the image with every
/// visited pixel's interpolation standing for the pixels around it.
SubPassCallback preview_after_subpass(const FrameContext& ctx, const DeepBuffer& deep, const IrradianceCache& cache,
                                      const std::function<void(const Image&)>& preview) {
    auto direct =
        std::make_shared<std::vector<Color>>(fragment_direct_radiance(ctx.scene, deep, ctx.materials, ctx.lighting, false, ctx.stats));
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

GatherSettings frame_gather_settings(const FrameContext& ctx, bool record_terms) {
    GatherSettings gs = gather_settings(ctx.scene);
    gs.record_terms = record_terms;  // brute force needs no gradients
    gs.hessian = record_terms && ctx.scene.render.cache.metric == Metric::Hessian;
    gs.cancel = ctx.cancel;
    return gs;
}

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
    std::vector<Indirect> light = ctx.comm.size() == 1
                                      ? gather_every_fragment(ctx.scene, deep, gatherer, ctx.stats, ctx.progress)
                                      : indirect_in_tiles(ctx.comm, deep, ctx.scene.render.parallel.tile_size, [&](const DeepBuffer& tile) {
                                            return gather_every_fragment(ctx.scene, tile, gatherer, ctx.stats, nullptr);
                                        });
    specular_brute_pass(ctx, gatherer, specular);
    ctx.stats.set("gathers", static_cast<double>(deep.fragments.size() + specular.brute.size()));
    ctx.stats.set("rays_per_gather", gatherer.grid().rays());
    return light;
}

}  // namespace bounce
