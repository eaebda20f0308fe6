// The radiosity textures' passes (frame_passes.h): made, loaded or carried for a frame's gathers,
// shared among an MPI job's ranks, saved.
#include "bounce/render/frame_passes.h"

#include <cstdio>

#include "bounce/radiosity/radiosity.h"

namespace bounce {

namespace {

/// The largest luminance a sky light sends.
float sky_brightest(const Light& l) {
    float top = luminance(l.color);
    if (l.sky_map) {
        float m = 0;
        for (size_t i = 0; i + 2 < l.sky_map->rgb.size(); i += 3)
            m = std::max(m, luminance(Color(l.sky_map->rgb[i], l.sky_map->rgb[i + 1], l.sky_map->rgb[i + 2])));
        top *= m;
    }
    return top;
}

}  // namespace

/// Under MPI: every process takes the sides the others baked (RadiosityTextures::take_baked).
void exchange_baked_sides(const FrameContext& ctx, RadiosityTextures& rt) {
    if (ctx.comm.size() == 1) return;
    const std::vector<std::string> all = ctx.comm.allgather(rt.baked_bytes());
    size_t bytes = 0;  // counted as exchange_bytes counts: what every rank sent
    for (size_t r = 0; r < all.size(); ++r) {
        bytes += all[r].size();
        if (static_cast<int>(r) != ctx.comm.rank()) rt.take_baked(all[r]);
    }
    ctx.stats.set("radiosity_sides_exchanged_bytes", static_cast<double>(bytes));
}

RadiosityResult radiosity_pass(const FrameContext& ctx, const RadiosityStep& step, const FramePlan& plan, const FrameState& previous) {
    RadiosityResult out;
    const RadiositySettings& settings = step.settings;
    out.textures = std::make_unique<RadiosityTextures>();
    if (step.source == RadiositySource::Carry) {
        PhaseTimer t(ctx.stats, "radiosity carry");
        *out.textures = RadiosityTextures::carry(*previous.radiosity, ctx.scene, ctx.materials, ctx.lighting, settings, *plan.changes,
                                                 out.changed, ctx.stats);
        // What a moving object can show or hide: the brightest texel, emission or sky.
        out.brightest = out.textures->brightest();
        for (const Material& m : ctx.scene.materials) out.brightest = std::max(out.brightest, luminance(m.peak_emission()));
        for (const Light& l : ctx.scene.lights)
            if (l.type == LightType::Sky) out.brightest = std::max(out.brightest, sky_brightest(l));
        return out;
    }
    if (step.source == RadiositySource::Load) {
        PhaseTimer t(ctx.stats, "radiosity load");
        std::string why;
        if (RadiosityTextures::load(step.folder, ctx.scene, settings, ctx.materials, ctx.lighting, *out.textures, why)) {
            ctx.stats.set("radiosity_reused", 1);
            return out;
        }
        if (ctx.progress) std::fprintf(stderr, "radiosity textures in %s not reused: %s; baking\n", step.folder.c_str(), why.c_str());
    }
    {
        PhaseTimer t(ctx.stats, "radiosity layout");  // every side's lattice laid out (pages come as they are baked)
        *out.textures = RadiosityTextures::lazy(ctx.scene, ctx.materials, ctx.lighting, settings);
    }
    ctx.stats.set("radiosity_reused", 0);
    if (step.source == RadiositySource::BakeSplit) {
        PhaseTimer t(ctx.stats, "radiosity");
        out.textures->bake_all(ctx.stats, ctx.progress, ctx.comm.rank(), ctx.comm.size());
        ctx.stats.set("radiosity_sides_split_here", static_cast<double>(out.textures->baked_sides()));
        exchange_baked_sides(ctx, *out.textures);
    }
    return out;
}

void finish_radiosity_pass(const FrameContext& ctx, const FinishRadiosityStep& step, RadiosityTextures& rt, size_t baked_before) {
    if (step.share) exchange_baked_sides(ctx, rt);
    const size_t baked = rt.baked_sides();
    ctx.stats.set("radiosity_sides_baked", static_cast<double>(baked - baked_before));
    ctx.stats.set("radiosity_sides", static_cast<double>(rt.sides()));
    ctx.stats.set("radiosity_bytes", static_cast<double>(rt.allocated_bytes()));
    ctx.stats.set("small_instances_lit_at_hit", static_cast<double>(rt.objects_lit_at_hit()));
    if (step.folder.empty() || baked == baked_before || ctx.comm.rank() != 0) return;  // rank 0 writes
    PhaseTimer t(ctx.stats, "radiosity save");
    rt.save(step.folder);
}

}  // namespace bounce
