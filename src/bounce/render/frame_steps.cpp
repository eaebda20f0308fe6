#include "bounce/render/frame_steps.h"

#include <variant>

#include "bounce/render/distributed.h"
#include "bounce/shade/layers.h"

namespace bounce {

namespace {

/// The shaded window's fragment colours at the gathered window's fragments (0 in its margin):
/// what write_deep takes. Empty when there are none (an MPI rank that shades no image).
std::vector<Color> colours_of_window(const VisibilityResult& deep, const std::vector<Color>& shaded) {
    const DeepBuffer &g = deep.gathered, &s = deep.shaded();
    if (shaded.size() != s.fragments.size()) return {};
    if (window_of(g) == window_of(s)) return shaded;
    std::vector<Color> out(g.fragments.size(), Color(0));
    for (int wy = 0; wy < s.height; ++wy)
        for (int wx = 0; wx < s.width; ++wx) {
            const size_t from = s.offsets[static_cast<size_t>(wy) * s.width + wx], n = s.pixel(wx, wy).size();
            const size_t to = g.offsets[static_cast<size_t>(wy + s.y0 - g.y0) * g.width + (wx + s.x0 - g.x0)];
            std::copy_n(shaded.begin() + static_cast<std::ptrdiff_t>(from), n, out.begin() + static_cast<std::ptrdiff_t>(to));
        }
    return out;
}

}  // namespace

FrameRun::FrameRun(const Scene& scene, const FramePlan& plan, const FrameState& previous, const RenderRequest& request, Stats& stats,
                   ProgressSink* progress)
    : scene_(scene), plan_(plan), previous_(previous), request_(request), stats_(stats), progress_(progress), materials_(scene) {
    result_.plan = plan;
    result_.cache_info = cache_file_info(scene, plan.frame);
}

void FrameRun::run(const PlannedStep& planned) {
    if (planned.when == RunWhen::ShadingMissed && shading_misses_ == 0) return;
    std::visit([this](const auto& s) { step(s); }, planned.step);
}

void FrameRun::step(const AccelStep& s) {
    if (s.source == AccelSource::Keep) {
        result_.accel = previous_.accel;
    } else {
        PhaseTimer t(stats_, "build BVH");
        result_.accel =
            std::make_shared<const SceneAccel>(scene_, s.lighting, s.source == AccelSource::Update ? previous_.accel.get() : nullptr);
    }
    const SceneAccel& accel = *result_.accel;
    if (const BvhReuse r = accel.reuse(); r.kept + r.refit + r.built > 0)
        stats_.set("bvh_parts", nlohmann::json{{"kept", r.kept}, {"refit", r.refit}, {"built", r.built}});
    stats_.set("ray_offset", accel.ray_offset());
    lighting_.emplace(scene_, accel, s.lighting);
    ctx_.emplace(FrameContext{scene_, plan_, accel, materials_, *lighting_, stats_, progress_, request_.cancel,
                              request_.comm ? *request_.comm : alone_});
}

void FrameRun::step(const VisibilityStep& s) { deep_ = visibility_pass(ctx(), s, plan_, previous_); }

void FrameRun::step(const RadiosityStep& s) { radiosity_ = radiosity_pass(ctx(), s, plan_, previous_); }

void FrameRun::step(const CacheStartStep& s) {
    start_ = cache_start_pass(ctx(), s, plan_, previous_, radiosity_);
    result_.records_loaded = start_.records_loaded;
    result_.cache_differences = start_.differences;
    result_.cache_other_lighting = start_.other_lighting;
    if (start_.other_lighting) stats_.set("cache_bounce_light_stale", 1);
    const TemporalJudgement& j = start_.judged;
    result_.temporal = {j.kept, j.moved, j.view, j.light, j.dropped, 0, 0, j.anchored, j.anchors_kept};
    if (!start_.differences.empty()) stats_.set("cache_reused_with_other_settings", nlohmann::json(start_.differences));
}

void FrameRun::step(const SpecularSitesStep& s) { specular_ = specular_sites_pass(ctx(), s, deep_.shaded()); }

template <class F>
void FrameRun::timed_gather(F&& gather) {
    PhaseTimer t(stats_, "gather");
    const uint64_t rays_before = stats_.total().gather_rays;
    gather();
    gather_s_ += t.stop();
    gather_rays_ += stats_.total().gather_rays - rays_before;
    stats_.set("gather_rays_per_s", gather_s_ > 0 ? static_cast<double>(gather_rays_) / gather_s_ : 0.0);
    result_.gathered = true;
}

void FrameRun::step(const GatherRecordsStep& s) {
    baked_before_ = radiosity_.textures ? radiosity_.textures->baked_sides() : 0;
    timed_gather([&] {
        gathered_ = record_gather_pass(ctx(), s, plan_, deep_, radiosity_.textures.get(), *start_.cache, start_.judged, request_.preview);
    });
    result_.records_new += gathered_.records_new;
    result_.temporal.regathered = gathered_.regathered, result_.temporal.reshaded = gathered_.reshaded;
}

void FrameRun::step(const RefineStep& s) {
    timed_gather([&] { refine_pass(ctx(), s, plan_, deep_, radiosity_.textures.get(), *start_.cache, start_.judged, gathered_); });
}

void FrameRun::step(const GatherSitesStep& s) {
    timed_gather(
        [&] { result_.records_new += site_gather_pass(ctx(), s, plan_, specular_.sites, radiosity_.textures.get(), *start_.cache); });
}

void FrameRun::step(const BruteGatherStep& s) {
    baked_before_ = radiosity_.textures ? radiosity_.textures->baked_sides() : 0;
    timed_gather([&] { brute_ = brute_gather_pass(ctx(), s, deep_.shaded(), radiosity_.textures.get(), specular_); });
}

void FrameRun::step(const ShadeStep& s) {
    const IrradianceCache* cache = s.indirect == IndirectFrom::Cache ? start_.cache.get() : nullptr;
    const std::vector<Indirect>* light = s.indirect == IndirectFrom::Brute ? &brute_ : nullptr;
    ShadeResult shaded = shading_pass(ctx(), s, deep_.shaded(), cache, light, specular_, radiosity_.textures.get(), request_.preview);
    shading_misses_ = shaded.shading_misses;
    deep_colour_ = s.deep_colour;
    result_.shading_misses = shaded.shading_misses;
    result_.image = std::move(shaded.image);
    result_.deep_colour = std::move(shaded.colours);
    // Empty refined mask: a rank that writes no image.
    if (cache && (s.refined_layer || cache->fragment_record_count() > 0) && !shaded.refined.empty())
        add_mask_layer(result_.image, shaded.refined, "refined");
}

void FrameRun::step(const FinishRadiosityStep& s) {
    if (radiosity_.textures) finish_radiosity_pass(ctx(), s, *radiosity_.textures, baked_before_);
}

RenderResult FrameRun::finish() {
    result_.fragment_records_new += gathered_.fragment_records_new;
    result_.waiting = std::move(gathered_.waiting);
    result_.gathers = std::move(gathered_.gathers);
    result_.cache = std::move(start_.cache);
    if (result_.cache) {
        stats_.set("records", static_cast<double>(result_.cache->size()));
        stats_.set("records_loaded", static_cast<double>(result_.records_loaded));
        if (plan_.find<GatherRecordsStep>()) stats_.set("records_new", static_cast<double>(result_.records_new));
        std::vector<Vec3> positions;
        for (size_t i = 0; i < result_.cache->size(); ++i) positions.push_back(result_.cache->record(i).p);
        add_records_layer(result_.image, scene_.camera, positions);
    }
    // Sources of a lazy bake point at this frame's materials and lights: only a shot's next
    // frame takes the textures (RadiosityTextures::carry points them at its own).
    result_.radiosity = std::move(radiosity_.textures);
    if (!plan_.deep_out.empty()) {
        result_.deep_colour = deep_colour_ ? colours_of_window(deep_, result_.deep_colour) : std::vector<Color>();
        result_.gathered_deep = std::make_shared<const DeepBuffer>(deep_.crop ? std::move(deep_.gathered) : deep_.gathered);
    } else {
        result_.deep_colour.clear();
    }
    // The passes are done with the fragments: moved, not copied (a Sponza frame's are 100 MB).
    result_.deep = deep_.crop ? std::move(*deep_.crop) : std::move(deep_.gathered);
    return std::move(result_);
}

}  // namespace bounce
