// The cache a frame starts from: none, the previous frame's (judged record by record in a
// shot), the session's, or a cache file.
#include "bounce/render/frame_passes.h"

#include "bounce/cache/cache_file.h"
#include "bounce/cache/temporal.h"

namespace bounce {

std::unique_ptr<IrradianceCache> copy_cache(const IrradianceCache& from, const Scene& scene) {
    if (from.made_like(scene.bounds(), from.settings(), from.ao_only())) return from.clone();
    auto cache = std::make_unique<IrradianceCache>(scene.bounds(), from.settings(), from.ao_only());
    cache->set_luminance_floor(from.luminance_floor());
    cache->set_light_scales(from.light_scales());
    for (size_t i = 0; i < from.size(); ++i) cache->insert_loaded(from.record(i));
    for (size_t i = 0; i < from.fragment_record_count(); ++i) cache->insert_fragment_record(from.fragment_record_at(i));
    return cache;
}

CacheStartResult cache_start_pass(const FrameContext& ctx, const CacheStartStep& step, const FramePlan& plan, const FrameState& previous,
                                  const RadiosityResult& radiosity) {
    const Scene& scene = ctx.scene;
    CacheStartResult out;
    PhaseTimer t(ctx.stats, "cache read");
    out.cache = std::make_unique<IrradianceCache>(scene.bounds(), plan.cache, step.ao);
    if (step.light_parts) out.cache->set_light_scales(light_scales(scene));
    if (step.start == CacheStart::Temporal) {
        // The previous frame's records and those still waiting from before, judged for this frame.
        out.judged = judge_records(*previous.cache, previous.waiting_records(), previous.kept_gathers(), *previous.scene, scene,
                                   *plan.changes, radiosity.changed, radiosity.brightest, plan.tiling().seed);
        out.cache->set_luminance_floor(previous.cache->luminance_floor());
        for (const Record& r : out.judged.valid) out.cache->insert_loaded(r);
        for (const Record& r : out.judged.fragment_valid) out.cache->insert_fragment_record(r);
        out.records_loaded = out.judged.valid.size();
        return out;
    }
    std::function<bool(const Record&)> keep;
    if (step.flush_crop)
        keep = [crop = plan.window, camera = CameraRays(scene.camera)](const Record& r) { return !camera.projects_into(r.p, crop); };
    if (step.start == CacheStart::Previous) {
        const IrradianceCache& from = *previous.cache;
        // Records that keep their light parts show today's light colours and intensities: the
        // bounce light of a light edit, exactly (docs/lighting-tool.md).
        std::vector<Color> scales = out.cache->light_scales();
        if (!keep && from.made_like(scene.bounds(), plan.cache, step.ao)) {
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
    if (step.start == CacheStart::File) {
        LoadedCache loaded = load_cache(step.cache_in, scene, step.force, step.reuse, *out.cache, keep);
        out.records_loaded = loaded.records;
        out.differences = loaded.differences;
        out.other_lighting = loaded.other_lighting;
    }
    return out;
}

}  // namespace bounce
