#include "bounce/render/frame_plan.h"

#include <fmt/format.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>

#include "bounce/accel/accel.h"
#include "bounce/cache/passes.h"
#include "bounce/core/error.h"
#include "bounce/core/memory.h"
#include "bounce/gather/guide.h"
#include "bounce/render/frame_passes.h"
#include "bounce/render/render.h"
#include "bounce/scene/keyframes.h"

namespace bounce {

int crop_margin(const Scene& scene) {
    const CacheSettings& c = scene.render.cache;
    return static_cast<int>(std::ceil(c.max_spacing * c.shading_reach)) + 1;
}

namespace {

const char* name(VisibilityStep s) {
    switch (s) {
        case VisibilityStep::Trace:
            return "trace";
        case VisibilityStep::ReadFile:
            return "read deep file";
        case VisibilityStep::Previous:
            return "previous frame's";
    }
    return "?";
}
const char* name(RadiosityStep s) {
    switch (s) {
        case RadiosityStep::None:
            return "none";
        case RadiosityStep::Bake:
            return "bake as hit";
        case RadiosityStep::BakeSplit:
            return "bake all, a share per rank, exchanged";
        case RadiosityStep::Load:
            return "load, bake what is missing";
        case RadiosityStep::Carry:
            return "previous frame's, re-bake what changed";
    }
    return "?";
}
const char* name(CacheStart s) {
    switch (s) {
        case CacheStart::None:
            return "none";
        case CacheStart::Empty:
            return "empty";
        case CacheStart::File:
            return "cache file";
        case CacheStart::Previous:
            return "previous frame's";
        case CacheStart::Temporal:
            return "previous frame's records, judged";
    }
    return "?";
}
const char* name(GatherStep s) {
    switch (s) {
        case GatherStep::None:
            return "none";
        case GatherStep::Brute:
            return "brute force";
        case GatherStep::Cache:
            return "gathering pass";
        case GatherStep::WhereMissing:
            return "only where records are missing";
    }
    return "?";
}

/// A re-shade or re-gather starts from the previous frame's deep buffer and cache when it holds them.
bool reuses_previous(const RenderRequest& request) { return request.kind == FrameKind::Reshade || request.kind == FrameKind::Regather; }

/// Where the cache starts: the previous frame's, a file, or empty (a full re-gather).
CacheStart cache_start(const Scene& scene, const FrameState& previous, const RenderRequest& request) {
    const bool cached = scene.render.indirect.gi == GiMode::Cache;
    const bool crop = scene.render.visibility.has_crop();
    // Without a cache render, a cache file is only read for its records layer.
    if (!cached) return request.cache_in.empty() ? CacheStart::None : CacheStart::File;
    if (request.kind == FrameKind::Regather && !crop) return CacheStart::Empty;
    if (request.kind == FrameKind::ShotFrame && previous.cache) return CacheStart::Temporal;
    if (reuses_previous(request) && previous.cache) return CacheStart::Previous;
    return request.cache_in.empty() ? CacheStart::Empty : CacheStart::File;
}

GatherStep gather_step(const Scene& scene, CacheStart cache, const RenderRequest& request) {
    const IndirectSettings& ind = scene.render.indirect;
    if (!ind.any()) return GatherStep::None;
    if (ind.gi != GiMode::Cache) return GatherStep::Brute;
    const bool starts_full = cache == CacheStart::Previous || cache == CacheStart::File || cache == CacheStart::Temporal;
    return request.kind == FrameKind::Reshade && starts_full ? GatherStep::WhereMissing : GatherStep::Cache;
}

/// Any light (or emissive material) of the shot keyed.
bool lights_keyed(const Scene& scene) {
    if (!scene.keyed.is_object()) return false;
    if (scene.keyed.contains("lights") && has_keys(scene.keyed["lights"])) return true;
    if (scene.keyed.contains("materials") && scene.keyed["materials"].is_object())
        for (const auto& [name, m] : scene.keyed["materials"].items())
            if (m.is_object() && m.contains("emission") && has_keys(m["emission"])) return true;
    return false;
}

/// What the frame cannot do, refused before any work: a frame larger than memory allows, and
/// what an MPI job's ranks cannot make together yet.
void refuse_what_cannot_run(const Scene& scene, const FramePlan& plan, const RenderRequest& request) {
    if (double need = estimate_render_bytes(scene), have = available_memory_bytes(); need > 0.8 * have)
        throw InputError(
            scene.path, "camera.resolution",
            fmt::format("a {}x{} frame needs about {:.2f} GiB; it may use {:.2f} GiB (80 % of the {:.2f} GiB available; "
                        "render a crop)",
                        scene.camera.width, scene.camera.height, need / 1073741824.0, 0.8 * have / 1073741824.0, have / 1073741824.0));
    if (request.comm && request.comm->size() > 1 && scene.render.shading.deep_colour && !plan.deep_out.empty())
        throw InputError(scene.path, "render.deep_colour", "a deep file with colour is written by one process (not under MPI yet)");
    if (request.comm && request.comm->size() > 1 && scene.render.cache.light_parts && scene.render.indirect.gi == GiMode::Cache)
        throw InputError(scene.path, "render.light_parts",
                         "records with light parts are made by one process (the lighting tool's; not under MPI)");
    // A rank's tiles find the pilots one process would only where tiles follow the pilots' grid.
    if (request.comm && request.comm->size() > 1 && scene.render.indirect.guided > 0 && scene.render.parallel.tile_size % kGuideBlock != 0)
        throw InputError(scene.path, "render.tile_size",
                         fmt::format("guided gathers under MPI need tiles of a multiple of {} pixels", kGuideBlock));
}

}  // namespace

FramePlan plan_frame(const Scene& scene, const FrameState& previous, const RenderRequest& request) {
    FramePlan plan;
    plan.frame = request.frame;
    plan.window = frame_window(scene);
    plan.gather_window = plan.window;
    if (scene.render.visibility.has_crop() && scene.render.indirect.gi == GiMode::Cache) {
        const int m = crop_margin(scene);
        const auto& w = plan.window;
        plan.gather_window = {std::max(0, w[0] - m), std::min(scene.camera.width, w[1] + m), std::max(0, w[2] - m),
                              std::min(scene.camera.height, w[3] + m)};
    }
    const bool shot = request.kind == FrameKind::ShotFrame;
    if (shot && previous.scene) plan.changes = std::make_shared<const SceneChanges>(scene_changes(*previous.scene, scene));
    const bool comparable = plan.changes && plan.changes->comparable;
    // (A previous deep buffer made for another camera or objects is refused by the pass, saying so;
    // a frame of a shot takes it only when its camera and objects are the same.)
    const bool same_view =
        previous.deep && previous.deep->scene_fingerprint == scene.visibility_fingerprint() && !scene.render.visibility.has_crop();
    if ((reuses_previous(request) && previous.deep) || (shot && same_view))
        plan.visibility = VisibilityStep::Previous;
    else if (!request.deep_in.empty())
        plan.visibility = VisibilityStep::ReadFile, plan.deep_in = request.deep_in;
    else
        plan.visibility = VisibilityStep::Trace;
    plan.deep_out = request.deep_out;

    // A later frame that refit a part the previous BVHs trace (the tool going back) leaves them stale.
    const bool accel_usable = previous.accel && previous.accel->current();
    if (comparable && accel_usable && plan.changes->visible_geometry_same)
        plan.accel = AccelStep::Keep;
    else if (shot && accel_usable)
        plan.accel = AccelStep::Update;
    plan.cache = cache_start(scene, previous, request);
    if (plan.cache == CacheStart::Temporal && !comparable) plan.cache = CacheStart::Empty;  // other objects: nothing to keep
    if (plan.cache == CacheStart::File) plan.cache_in = request.cache_in;
    plan.flush_crop = request.kind == FrameKind::Regather && scene.render.visibility.has_crop() && plan.cache != CacheStart::Empty;
    plan.force = request.force;
    plan.cache_reuse = request.cache_reuse;
    plan.gather = gather_step(scene, plan.cache, request);
    const bool specular = std::any_of(scene.materials.begin(), scene.materials.end(), [](const Material& m) { return m.is_specular(); });
    plan.specular_sites = specular && SpecularSitesResult::lit_by_gathers(scene);
    plan.refine = (plan.gather == GatherStep::Cache || plan.gather == GatherStep::WhereMissing) && refinement_runs(scene);
    plan.correct = scene.render.indirect.any() && scene.render.indirect.gi == GiMode::Cache && scene.render.cache.correction_rays > 0;
    const IndirectSettings& ind = scene.render.indirect;
    if (plan.gather != GatherStep::None && scene.render.radiosity.enabled && !ind.ao)
        plan.radiosity = scene.render.radiosity.folder.empty() ? RadiosityStep::Bake : RadiosityStep::Load;
    // Textures with light parts are baked, not loaded (files hold the sum), and carried only
    // between frames that keep parts for as many lights.
    const bool parts = scene.render.cache.light_parts;
    if (parts && plan.radiosity == RadiosityStep::Load) plan.radiosity = RadiosityStep::Bake;
    // An MPI job's still bakes every side once, a share per rank, instead of each rank baking
    // what its own gathers hit (about half the sides each on Sponza at 2 ranks, more as ranks
    // grow; docs/parallel.md measures both). Not for a shot (its next frame re-bakes only the
    // sides baked before, as one process does) nor for saved textures (Load: they hold the
    // sides one process would bake).
    if (plan.radiosity == RadiosityStep::Bake && request.comm && request.comm->size() > 1 && !shot)
        plan.radiosity = RadiosityStep::BakeSplit;
    if (plan.radiosity != RadiosityStep::None && comparable && previous.radiosity && previous.radiosity->has_parts() == parts &&
        (!parts || previous.scene->lights.size() == scene.lights.size()))
        plan.radiosity = RadiosityStep::Carry;
    plan.share_radiosity = plan.radiosity != RadiosityStep::None && request.comm && request.comm->size() > 1 &&
                           (shot || !scene.render.radiosity.folder.empty());
    // A shot in which anything moves keeps records' hits: a record is then updated (the rays a
    // moving object may meet traced again, every hit re-shaded) rather than gathered again.
    plan.keep_hits = shot && scene.render.indirect.gi == GiMode::Cache && (lights_keyed(scene) || scene.objects_move());
    // Refinement's gathers lend their rays to the next frames' (EarlierGathers; not with light
    // parts: per-light layers of a shot are not measured with it). In an MPI job every process
    // takes every process's gathers with their hits (refinement_pass), so each reuses the same.
    plan.keep_gathers = shot && plan.refine && scene.render.cache.temporal_refine_reuse > 0 && !parts;
    plan.preview = scene.render.parallel.preview && request.preview != nullptr;
    plan.threads = scene.render.parallel.threads > 0 ? scene.render.parallel.threads : tbb::this_task_arena::max_concurrency();
    refuse_what_cannot_run(scene, plan, request);
    return plan;
}

nlohmann::json FramePlan::describe() const {
    return {{"frame", frame},
            {"window", window},
            {"gather_window", gather_window},
            {"visibility", name(visibility)},
            {"deep_out", !deep_out.empty()},
            {"accel", accel == AccelStep::Keep     ? "keep"
                      : accel == AccelStep::Update ? "update"
                                                   : "build"},
            {"keep_hits", keep_hits},
            {"radiosity", name(radiosity)},
            {"share_radiosity", share_radiosity},
            {"cache", name(cache)},
            {"flush_crop", flush_crop},
            {"specular_sites", specular_sites},
            {"gather", name(gather)},
            {"refine", refine},
            {"correct", correct},
            {"keep_gathers", keep_gathers},
            {"threads", threads}};
}

}  // namespace bounce
