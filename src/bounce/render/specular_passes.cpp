// The passes of a frame for mirrors and glass (frame_passes.h): the sites of their paths and the
// light the shading pass gives them (their records and gathers are gather_pass.cpp's).
#include "bounce/cache/passes.h"
#include "bounce/render/distributed.h"
#include "bounce/render/frame_passes.h"
#include "bounce/specular/specular.h"

namespace bounce {

SpecularSitesResult specular_sites_pass(const FrameContext& ctx, const SpecularSitesStep& step, const DeepBuffer& shaded) {
    SpecularSitesResult out;
    const SpecularTracer tracer(ctx.scene, ctx.accel, ctx.lighting, ctx.materials, step.depth);
    PhaseTimer t(ctx.stats, "specular paths");
    out.sites = specular_sites(ctx.scene, shaded, tracer, ctx.plan.tiling().tile_size, ctx.stats, ctx.progress);
    ctx.stats.set("specular_sites", static_cast<double>(out.sites.fragments.size()));
    return out;
}

SiteLightResult site_light_for(const FrameContext& ctx, SiteLightFrom from, const SpecularSitesResult& specular,
                               const std::array<int, 4>& window, const IrradianceCache* cache, const RadiosityTextures* radiosity) {
    SiteLightResult out;
    // The shading pass traces the paths to these sites itself and looks them up in the textures.
    if (from == SiteLightFrom::Radiosity) {
        out.radiosity = radiosity;
        return out;
    }
    if (!specular.any()) return out;
    const bool whole = window_of(specular.sites) == window;
    out.sites = whole ? specular.sites : sub_window(specular.sites, window);
    switch (from) {
        case SiteLightFrom::None:  // direct light only (or AO): nothing to give
        case SiteLightFrom::Radiosity:
            break;
        case SiteLightFrom::Cache: {
            InterpolatedLight light = interpolation_pass(ctx.scene, out.sites, *cache, ctx.plan.tiling(), ctx.stats, nullptr, false);
            out.light = std::move(light.light);
            out.misses = light.misses;
            out.has_light = true;
            break;
        }
        case SiteLightFrom::Brute:
            if (specular.brute.empty()) break;
            out.light = whole ? specular.brute : window_slice(specular.sites, specular.brute, window);
            out.has_light = true;
            break;
    }
    return out;
}

}  // namespace bounce
