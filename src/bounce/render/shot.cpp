#include "bounce/render/shot.h"

#include "bounce/cache/cache_identity.h"

namespace bounce {

RenderResult Shot::render(const std::shared_ptr<const Scene>& scene, RenderRequest request, Stats& stats, ProgressSink* progress) {
    request.kind = FrameKind::ShotFrame;
    const FramePlan plan = plan_frame(*scene, state_, request);
    return run_frame(*scene, plan, state_, request, stats, progress);
}

void Shot::keep(RenderResult& result, const std::shared_ptr<const Scene>& scene) {
    state_ = result.release_state();
    state_.scene = scene;
}

void Shot::start_from(const std::shared_ptr<const Scene>& before, const std::string& cache_file) {
    // The cache the frame before would have left: made as its plan makes one.
    RenderRequest request;
    request.kind = FrameKind::ShotFrame;
    const FramePlan plan = plan_frame(*before, {}, request);
    const CacheStartStep* start = plan.find<CacheStartStep>();
    auto cache = std::make_shared<IrradianceCache>(before->bounds(), plan.cache, start && start->ao);
    if (start && start->light_parts) cache->set_light_scales(light_scales(*before));
    // Its own frame's scene and settings: only other settings are refused.
    load_cache(cache_file, *before, true, CacheReuse::Strict, *cache);
    state_ = {};
    state_.cache = std::move(cache);
    state_.scene = before;
}

}  // namespace bounce
