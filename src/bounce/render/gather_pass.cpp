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

/// What the redoing of a shot's earlier records needs to know of this frame.
TemporalFrame temporal_frame(const FrameContext& ctx, const FramePlan& plan, bool keep_hits) {
    return {ctx.scene, plan.changes.get(), plan.frame, keep_hits, plan.tiling().seed, plan.cache};
}

/// The preview callback of the gathering pass: after each sub-pass, the image with every
/// visited pixel's interpolation standing for the pixels around it.
SubPassCallback preview_after_subpass(const FrameContext& ctx, const DeepBuffer& deep, const IrradianceCache& cache,
                                      const std::function<void(const Image&)>& preview) {
    auto direct = std::make_shared<std::vector<Color>>(
        fragment_direct_radiance(ctx.scene, deep, ctx.materials, ctx.lighting, ctx.plan.tiling().seed, false, ctx.stats));
    auto visited = std::make_shared<std::vector<uint8_t>>(deep.pixel_count(), 0);
    return [&ctx, &deep, &cache, preview, direct, visited](const SubPass& sp, size_t, size_t) {
        for (int wy = 0; wy < deep.height; ++wy)
            for (int wx = 0; wx < deep.width; ++wx)
                if (sp.contains(wx + deep.x0, wy + deep.y0)) (*visited)[static_cast<size_t>(wy) * deep.width + wx] = 1;
        std::vector<Indirect> pre = preview_indirect(ctx.scene, deep, cache, *visited, sp.step);
        preview(shade(ctx.scene, deep, ctx.materials, ctx.lighting, ctx.plan.shade(), &pre, ctx.stats, nullptr, direct.get()));
    };
}

}  // namespace

GatherSettings frame_gather_settings(const FrameContext& ctx, bool record_terms, bool hessian) {
    GatherSettings gs = ctx.plan.gather;
    gs.record_terms = record_terms;  // brute force needs no gradients
    gs.hessian = record_terms && hessian;
    gs.cancel = ctx.cancel;
    return gs;
}

GatherPassResult record_gather_pass(const FrameContext& ctx, const GatherRecordsStep& step, const FramePlan& plan,
                                    const VisibilityResult& deep, const RadiosityTextures* radiosity, IrradianceCache& cache,
                                    TemporalJudgement& judged, const std::function<void(const Image&)>& preview) {
    const Scene& scene = ctx.scene;
    const GatherSettings gs = frame_gather_settings(ctx, true, step.hessian);
    Gatherer gatherer(scene, ctx.accel, ctx.materials, ctx.lighting, radiosity, gs);
    GatherPassResult out;
    const size_t before = cache.size();
    GatheringOptions options;
    options.frame = plan.frame;
    options.keep_hits = step.keep_hits;
    options.comm = &ctx.comm;
    options.sharing = step.sharing;
    if (step.own_weight > 0) options.own_weight = step.own_weight;
    if (step.preview && preview) options.after_subpass = preview_after_subpass(ctx, deep.shaded(), cache, preview);
    std::unique_ptr<Gatherer> first;
    if (step.first_rays > 0) {
        GatherSettings fs = gs;
        fs.rays = step.first_rays;
        first = std::make_unique<Gatherer>(scene, ctx.accel, ctx.materials, ctx.lighting, radiosity, fs);
        options.first = first.get();
    }
    std::unique_ptr<StaleRecords> stale;
    if (!judged.stale.empty()) {
        stale = std::make_unique<StaleRecords>(std::move(judged.stale), std::move(judged.why), scene.bounds(), cache.settings(),
                                               cache.ao_only(), redo_function(temporal_frame(ctx, plan, step.keep_hits), cache, gatherer));
        options.stale = stale.get();
    }
    gathering_pass(scene, deep.gathered, gatherer, cache, ctx.stats, ctx.progress, options);
    if (stale) {
        out.regathered = stale->regathered, out.reshaded = stale->reshaded;
        out.waiting = stale->waiting();
    }
    out.records_new = cache.size() - before - out.regathered - out.reshaded;  // made this frame
    out.after_subpass = std::move(options.after_subpass);
    return out;
}

void refine_pass(const FrameContext& ctx, const RefineStep& step, const FramePlan& plan, const VisibilityResult& deep,
                 const RadiosityTextures* radiosity, IrradianceCache& cache, TemporalJudgement& judged, GatherPassResult& gathered) {
    const Scene& scene = ctx.scene;
    // A refined fragment's gather feeds that fragment only: no gradients needed.
    GatherSettings own = frame_gather_settings(ctx, false);
    own.rays = step.rays;
    Gatherer refiner(scene, ctx.accel, ctx.materials, ctx.lighting, radiosity, own);
    // Over the frame's window only: the margin's fragments are never shaded.
    RefinementOptions ro;
    ro.frame = plan.frame;
    ro.keep_hits = step.keep_rays;  // the next frames reuse refinement's rays
    ro.comm = &ctx.comm;
    if (!judged.fragment_stale.empty()) {
        ro.stale = &judged.fragment_stale;
        ro.update = fragment_update_function(temporal_frame(ctx, plan, step.keep_rays), refiner, cache);
    }
    std::unique_ptr<EarlierGathers> earlier;
    if (step.keep_gathers) {
        earlier = std::make_unique<EarlierGathers>(std::move(judged.earlier_gathers), scene.bounds(), step.reuse);
        ro.earlier = earlier.get();
    }
    std::unique_ptr<EarlierGathers> refined_before;
    if (step.refined_before) {
        refined_before = refined_the_frame_before(cache, judged, scene, plan.cache, plan.frame);
        ro.refined_before = refined_before.get();
    }
    const size_t made = refinement_pass(scene, deep.shaded(), refiner, cache, ctx.stats, ctx.progress, ro);
    gathered.fragment_records_new += made;
    if (earlier) gathered.gathers = gathers_to_keep(*earlier, cache, plan.frame);
    if (made > 0 && gathered.after_subpass) {
        const auto schedule = subpass_schedule(1);
        gathered.after_subpass(schedule.back(), schedule.size() - 1, schedule.size());
    }
}

size_t site_gather_pass(const FrameContext& ctx, const GatherSitesStep& step, const FramePlan& plan, const DeepBuffer& sites,
                        const RadiosityTextures* radiosity, IrradianceCache& cache) {
    if (sites.fragments.empty()) return 0;
    const Gatherer gatherer(ctx.scene, ctx.accel, ctx.materials, ctx.lighting, radiosity, frame_gather_settings(ctx, true, step.hessian));
    const size_t before = cache.size();
    GatheringOptions options;
    options.frame = plan.frame;
    options.keep_hits = step.keep_hits;
    options.comm = &ctx.comm;
    gathering_pass(ctx.scene, sites, gatherer, cache, ctx.stats, ctx.progress, options);
    const size_t made = cache.size() - before;
    ctx.stats.set("specular_site_records", static_cast<double>(made));
    return made;
}

std::vector<Indirect> brute_gather_pass(const FrameContext& ctx, const BruteGatherStep& step, const DeepBuffer& deep,
                                        const RadiosityTextures* radiosity, SpecularSitesResult& specular) {
    Gatherer gatherer(ctx.scene, ctx.accel, ctx.materials, ctx.lighting, radiosity, frame_gather_settings(ctx, false));
    const auto every_fragment = [&](const DeepBuffer& of) {
        return ctx.comm.size() == 1 ? gather_every_fragment(ctx.scene, of, gatherer, ctx.stats, ctx.progress)
                                    : indirect_in_tiles(ctx.comm, of, ctx.plan.tiling().tile_size, [&](const DeepBuffer& tile) {
                                          return gather_every_fragment(ctx.scene, tile, gatherer, ctx.stats, nullptr);
                                      });
    };
    std::vector<Indirect> light = every_fragment(deep);
    if (step.sites && specular.any()) specular.brute = every_fragment(specular.sites);
    ctx.stats.set("gathers", static_cast<double>(deep.fragments.size() + specular.brute.size()));
    ctx.stats.set("rays_per_gather", gatherer.grid().rays());
    return light;
}

}  // namespace bounce
