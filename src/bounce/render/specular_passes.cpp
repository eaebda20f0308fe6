// The passes of a frame for mirrors and glass (frame_passes.h): the sites of their paths, the
// records and gathers that light them, and the light the shading pass gives them.
#include <mutex>
#include <shared_mutex>

#include "bounce/cache/passes.h"
#include "bounce/render/distributed.h"
#include "bounce/render/frame_passes.h"
#include "bounce/specular/specular.h"

namespace bounce {

bool SpecularSitesResult::lit_by_gathers(const Scene& scene) {
    return scene.render.shading.indirect_at_specular_hits == SpecularHitLight::Cache && scene.render.indirect.any() &&
           !scene.render.indirect.ao;
}

SpecularSitesResult specular_sites_pass(const FrameContext& ctx, const FramePlan& plan, const DeepBuffer& shaded) {
    SpecularSitesResult out;
    const SpecularTracer tracer(ctx.scene, ctx.accel, ctx.lighting, ctx.materials);
    out.mirrors = tracer.active();
    // Without gathers to light them (direct light only, AO, radiosity textures) the shading
    // pass traces the paths itself and needs no sites.
    if (!plan.specular_sites) return out;
    PhaseTimer t(ctx.stats, "specular paths");
    out.sites = specular_sites(ctx.scene, shaded, tracer, ctx.stats, ctx.progress);
    ctx.stats.set("specular_sites", static_cast<double>(out.sites.fragments.size()));
    return out;
}

size_t specular_gather_pass(const FrameContext& ctx, const FramePlan& plan, const DeepBuffer& sites, const Gatherer& gatherer,
                            IrradianceCache& cache) {
    if (sites.fragments.empty() || !SpecularSitesResult::lit_by_gathers(ctx.scene)) return 0;
    const size_t before = cache.size();
    GatheringOptions options;
    options.frame = plan.frame;
    options.keep_hits = plan.keep_hits;
    options.comm = &ctx.comm;
    gathering_pass(ctx.scene, sites, gatherer, cache, ctx.stats, ctx.progress, options);
    const size_t made = cache.size() - before;
    ctx.stats.set("specular_site_records", static_cast<double>(made));
    return made;
}

void specular_brute_pass(const FrameContext& ctx, const Gatherer& gatherer, SpecularSitesResult& specular) {
    if (!specular.any() || !SpecularSitesResult::lit_by_gathers(ctx.scene)) return;
    const DeepBuffer& sites = specular.sites;
    specular.brute = ctx.comm.size() == 1
                         ? gather_every_fragment(ctx.scene, sites, gatherer, ctx.stats, ctx.progress)
                         : indirect_in_tiles(ctx.comm, sites, ctx.scene.render.parallel.tile_size, [&](const DeepBuffer& tile) {
                               return gather_every_fragment(ctx.scene, tile, gatherer, ctx.stats, nullptr);
                           });
}

SiteLightResult site_light_for(const FrameContext& ctx, const SpecularSitesResult& specular, const std::array<int, 4>& window,
                               const IrradianceCache* cache, const RadiosityTextures* radiosity) {
    SiteLightResult out;
    if (!specular.any()) return out;
    const Scene& scene = ctx.scene;
    const bool whole = window_of(specular.sites) == window;
    out.sites = whole ? specular.sites : sub_window(specular.sites, window);
    if (scene.render.shading.indirect_at_specular_hits == SpecularHitLight::Radiosity) {
        out.radiosity = radiosity;
    } else if (!SpecularSitesResult::lit_by_gathers(scene)) {
        // Direct light only (or AO): nothing to give.
    } else if (cache && scene.render.indirect.gi == GiMode::Cache) {
        InterpolatedLight light = interpolation_pass(scene, out.sites, *cache, ctx.stats, nullptr, false);
        out.light = std::move(light.light);
        out.misses = light.misses;
        out.has_light = true;
    } else if (!specular.brute.empty()) {
        out.light = whole ? specular.brute : window_slice(specular.sites, specular.brute, window);
        out.has_light = true;
    }
    return out;
}

}  // namespace bounce
