#include "bounce/render/frame_plan.h"

#include <fmt/format.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <optional>

#include "bounce/accel/accel.h"
#include "bounce/cache/passes.h"
#include "bounce/core/error.h"
#include "bounce/core/memory.h"
#include "bounce/gather/guide.h"
#include "bounce/render/frame_passes.h"
#include "bounce/render/render.h"
#include "bounce/scene/keyframes.h"

namespace bounce {

int crop_margin(const CacheSettings& c) { return static_cast<int>(std::ceil(c.max_spacing * c.shading_reach)) + 1; }

namespace {

const char* name(DeepSource s) {
    switch (s) {
        case DeepSource::Trace:
            return "trace";
        case DeepSource::ReadFile:
            return "read deep file";
        case DeepSource::Previous:
            return "previous frame's";
    }
    return "?";
}
const char* name(AccelSource s) {
    switch (s) {
        case AccelSource::Build:
            return "build";
        case AccelSource::Keep:
            return "keep";
        case AccelSource::Update:
            return "update";
    }
    return "?";
}
const char* name(RadiositySource s) {
    switch (s) {
        case RadiositySource::Bake:
            return "bake as hit";
        case RadiositySource::BakeSplit:
            return "bake all, a share per rank, exchanged";
        case RadiositySource::Load:
            return "load, bake what is missing";
        case RadiositySource::Carry:
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
const char* name(IndirectFrom s) {
    switch (s) {
        case IndirectFrom::None:
            return "none";
        case IndirectFrom::Brute:
            return "brute force";
        case IndirectFrom::Cache:
            return "cache";
    }
    return "?";
}
const char* name(SiteLightFrom s) {
    switch (s) {
        case SiteLightFrom::None:
            return "none";
        case SiteLightFrom::Radiosity:
            return "radiosity";
        case SiteLightFrom::Cache:
            return "cache";
        case SiteLightFrom::Brute:
            return "brute force";
    }
    return "?";
}

/// Which gathering a frame runs (the plan lists its steps).
enum class Gathering : uint8_t {
    None,          ///< direct light only
    Brute,         ///< a gather at every fragment
    Cache,         ///< gathering pass (and refinement) where the starting cache misses
    WhereMissing,  ///< shade the starting cache; only if a fragment has no record, gather and shade again
};

/// Frames of a shot: a point where a kept record weighs this much is covered by it alone (its
/// centre moved a little in the image since the frame that made it). Measured on shot A; asking
/// only 1 of kept records saved 9 % of its rays for 0.15 points more error and 7 % more flicker
/// (docs/animation.md).
constexpr float kTemporalOwnWeight = 0.9f;

/// What a plan decides from: the scene, the previous frame's state, the request, and what
/// follows from them once.
struct Inputs {
    const Scene& scene;
    const FrameState& previous;
    const RenderRequest& request;
    bool shot;        ///< a frame of a shot
    bool comparable;  ///< a shot's frame whose objects are the previous frame's
    bool cached;      ///< gi cache
    bool parts;       ///< records and textures keep per-light parts
};

/// A re-shade or re-gather starts from the previous frame's deep buffer and cache when it holds them.
bool reuses_previous(const RenderRequest& request) { return request.kind == FrameKind::Reshade || request.kind == FrameKind::Regather; }

DeepSource deep_source(const Inputs& in) {
    const Scene& scene = in.scene;
    // (A previous deep buffer made for another camera or objects is refused by the pass, saying
    // so; a frame of a shot takes it only when its camera and objects are the same.)
    const bool same_view =
        in.previous.deep && in.previous.deep->scene_fingerprint == scene.visibility_fingerprint() && !scene.render.visibility.has_crop();
    if ((reuses_previous(in.request) && in.previous.deep) || (in.shot && same_view)) return DeepSource::Previous;
    return in.request.deep_in.empty() ? DeepSource::Trace : DeepSource::ReadFile;
}

AccelSource accel_source(const Inputs& in, const SceneChanges* changes) {
    // A later frame that refit a part the previous BVHs trace (the tool going back) leaves them stale.
    const bool usable = in.previous.accel && in.previous.accel->current();
    if (in.comparable && usable && changes->visible_geometry_same) return AccelSource::Keep;
    return in.shot && usable ? AccelSource::Update : AccelSource::Build;
}

/// Where the cache starts: the previous frame's, a file, or empty (a full re-gather).
CacheStart cache_start(const Inputs& in) {
    const RenderRequest& request = in.request;
    // Without a cache render, a cache file is only read for its records layer.
    if (!in.cached) return request.cache_in.empty() ? CacheStart::None : CacheStart::File;
    if (request.kind == FrameKind::Regather && !in.scene.render.visibility.has_crop()) return CacheStart::Empty;
    if (request.kind == FrameKind::ShotFrame && in.previous.cache) return in.comparable ? CacheStart::Temporal : CacheStart::Empty;
    if (reuses_previous(request) && in.previous.cache) return CacheStart::Previous;
    return request.cache_in.empty() ? CacheStart::Empty : CacheStart::File;
}

Gathering gathering(const Inputs& in, CacheStart start) {
    if (!in.scene.render.indirect.any()) return Gathering::None;
    if (!in.cached) return Gathering::Brute;
    const bool starts_full = start == CacheStart::Previous || start == CacheStart::File || start == CacheStart::Temporal;
    return in.request.kind == FrameKind::Reshade && starts_full ? Gathering::WhereMissing : Gathering::Cache;
}

/// Where the radiosity textures come from (none: no gather, AO, or render.radiosity off).
std::optional<RadiositySource> radiosity_source(const Inputs& in, Gathering g) {
    const Scene& scene = in.scene;
    if (g == Gathering::None || !scene.render.radiosity.enabled || scene.render.indirect.ao) return std::nullopt;
    // Textures with light parts are baked, not loaded (files hold the sum), and carried only
    // between frames that keep parts for as many lights.
    RadiositySource s = scene.render.radiosity.folder.empty() || in.parts ? RadiositySource::Bake : RadiositySource::Load;
    // An MPI job's still bakes every side once, a share per rank, instead of each rank baking
    // what its own gathers hit (about half the sides each on Sponza at 2 ranks, more as ranks
    // grow; docs/parallel.md measures both). Not for a shot (its next frame re-bakes only the
    // sides baked before, as one process does) nor for saved textures (Load: they hold the
    // sides one process would bake).
    const bool ranks = in.request.comm && in.request.comm->size() > 1;
    if (s == RadiositySource::Bake && ranks && !in.shot) s = RadiositySource::BakeSplit;
    const FrameState& p = in.previous;
    if (in.comparable && p.radiosity && p.radiosity->has_parts() == in.parts &&
        (!in.parts || p.scene->lights.size() == scene.lights.size()))
        s = RadiositySource::Carry;
    return s;
}

/// Whether the refinement pass has anything to judge: `refine` > 0, or `refine_tilt` > 0 with
/// records on the un-displaced surface of a displaced object.
bool refinement_runs(const Scene& scene) {
    const CacheSettings& cs = scene.render.cache;
    if (cs.refine > 0) return true;
    if (cs.refine_tilt <= 0 || cs.displaced_records != RecordSurface::Undisplaced) return false;
    return std::any_of(scene.objects.begin(), scene.objects.end(), [](const Object& o) { return o.displacement_bound > 0; });
}

/// Every gather's settings: the automatic AO distance resolved; light parts and what records
/// predict for the control variate only where the cache keeps them.
GatherSettings gather_settings(const Scene& scene, const FrameTiling& tiling) {
    const IndirectSettings& r = scene.render.indirect;
    const CacheSettings& c = scene.render.cache;
    GatherSettings g;
    static_cast<IndirectSettings&>(g) = r;
    g.tiling = tiling;
    g.ao_distance = r.ao_distance >= 0 ? r.ao_distance : 0.1f * scene.size();
    g.light_parts = c.light_parts && r.gi == GiMode::Cache;
    g.prediction = c.correction_rays > 0 && r.gi == GiMode::Cache;
    g.prediction_hits = g.prediction && c.correction_prediction == CorrectionPrediction::Hits;
    return g;
}

/// Whether gathers light the sites of mirrors and glass (indirect_at_specular_hits = cache).
bool sites_lit_by_gathers(const Scene& scene) {
    return scene.render.shading.indirect_at_specular_hits == SpecularHitLight::Cache && scene.render.indirect.any() &&
           !scene.render.indirect.ao;
}

/// What the frame cannot do, refused before any work: a frame larger than memory allows, and
/// what an MPI job's ranks cannot make together yet.
void refuse_what_cannot_run(const Scene& scene, const FramePlan& plan, const RenderRequest& request) {
    if (double need = estimate_render_bytes(plan.window), have = available_memory_bytes(); need > 0.8 * have)
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

namespace {

/// The steps that make records where fragments need them: radiosity textures first when the
/// plan has not made them yet, the gathering pass, refinement, the sites of mirrors and glass.
void add_record_gathers(FramePlan& plan, const Inputs& in, std::optional<RadiosityStep> radiosity_first, bool sites, RunWhen when) {
    const Scene& scene = in.scene;
    const CacheSettings& c = scene.render.cache;
    const CacheStart start = plan.cache_start();
    if (radiosity_first) plan.steps.push_back({*radiosity_first, when});
    GatherRecordsStep g;
    g.hessian = c.metric == Metric::Hessian;
    g.first_rays = c.min_rays > 0 && c.min_rays < scene.render.indirect.rays ? c.min_rays : 0;
    g.own_weight = start == CacheStart::Temporal ? kTemporalOwnWeight : 0;
    // A shot in which anything moves keeps records' hits: a record is then updated (the rays a
    // moving object may meet traced again, every hit re-shaded) rather than gathered again.
    g.keep_hits = in.shot && (keys_light(scene.keyed) || scene.objects_move());
    g.preview = scene.render.parallel.preview && in.request.preview != nullptr;
    g.sharing = scene.render.parallel.cache_sharing;
    plan.steps.push_back({g, when});
    if (refinement_runs(scene)) {
        RefineStep r;
        r.rays = c.refine_rays > 0 ? c.refine_rays : scene.render.indirect.rays;
        // Refinement's gathers lend their rays to the next frames' (EarlierGathers; not with
        // light parts: per-light layers of a shot are not measured with it). In an MPI job every
        // process takes every process's gathers with their hits, so each reuses the same.
        r.keep_gathers = in.shot && c.temporal_refine_reuse > 0 && !in.parts;
        r.keep_rays = g.keep_hits || r.keep_gathers;
        r.refined_before = start == CacheStart::Temporal && plan.changes && plan.changes->camera;
        r.reuse = c.temporal_refine_reuse;
        plan.steps.push_back({r, when});
    }
    if (sites) plan.steps.push_back({GatherSitesStep{g.hessian, g.keep_hits}, when});
}

ShadeStep shade_step(const Inputs& in, Gathering g, bool specular) {
    const Scene& scene = in.scene;
    ShadeStep s;
    s.indirect = g == Gathering::None ? IndirectFrom::None : g == Gathering::Brute ? IndirectFrom::Brute : IndirectFrom::Cache;
    if (!specular)
        s.sites = SiteLightFrom::None;
    else if (scene.render.shading.indirect_at_specular_hits == SpecularHitLight::Radiosity)
        s.sites = SiteLightFrom::Radiosity;
    else if (sites_lit_by_gathers(scene))
        s.sites = s.indirect == IndirectFrom::Cache ? SiteLightFrom::Cache : SiteLightFrom::Brute;
    else
        s.sites = SiteLightFrom::None;  // direct light only, or AO
    if (s.indirect == IndirectFrom::Cache) {
        s.correction_rays = scene.render.cache.correction_rays;
        s.per_light = scene.render.shading.layers == LayerSet::Components && !scene.render.indirect.ao && !scene.lights.empty();
        s.refined_layer = refinement_runs(scene);
    }
    s.deep_colour = scene.render.shading.deep_colour;
    return s;
}

/// The steps from the radiosity textures (where the plan makes them) to the image.
void add_light_steps(FramePlan& plan, const Inputs& in, Gathering g, std::optional<RadiosityStep> radiosity) {
    const Scene& scene = in.scene;
    const bool specular = std::any_of(scene.materials.begin(), scene.materials.end(), [](const Material& m) { return m.is_specular(); });
    const bool sites = specular && sites_lit_by_gathers(scene);
    if (sites) plan.steps.push_back({SpecularSitesStep{scene.render.shading.specular_depth}});
    // Paths to mirrors and glass look their sites up in the textures: made before any shading.
    if (radiosity && specular && scene.render.shading.indirect_at_specular_hits == SpecularHitLight::Radiosity) {
        plan.steps.push_back({*radiosity});
        radiosity.reset();
    }
    const ShadeStep shade = shade_step(in, g, specular);
    switch (g) {
        case Gathering::None:
            break;
        case Gathering::Brute:
            if (radiosity) plan.steps.push_back({*radiosity});
            plan.steps.push_back({BruteGatherStep{sites}});
            break;
        case Gathering::Cache:
            add_record_gathers(plan, in, radiosity, sites, RunWhen::Always);
            break;
        case Gathering::WhereMissing: {
            ShadeStep first = shade;
            first.quick_look = scene.render.parallel.preview && in.request.preview != nullptr;
            plan.steps.push_back({first});
            add_record_gathers(plan, in, radiosity, sites, RunWhen::ShadingMissed);
            plan.steps.push_back({shade, RunWhen::ShadingMissed});
            return;
        }
    }
    plan.steps.push_back({shade});
}

}  // namespace

FramePlan plan_frame(const Scene& scene, const FrameState& previous, const RenderRequest& request) {
    FramePlan plan;
    plan.frame = request.frame;
    const RenderSettings& rs = scene.render;
    plan.window = frame_window(scene.camera, rs.visibility);
    plan.gather = gather_settings(scene, {rs.visibility.seed, rs.parallel.tile_size, rs.parallel.tile_order});
    plan.cache = rs.cache;
    plan.shading = rs.shading;
    plan.gather_window = plan.window;
    const bool crop = scene.render.visibility.has_crop();
    const bool cached = scene.render.indirect.gi == GiMode::Cache;
    if (crop && cached) {
        const int m = crop_margin(rs.cache);
        const auto& w = plan.window;
        plan.gather_window = {std::max(0, w[0] - m), std::min(scene.camera.width, w[1] + m), std::max(0, w[2] - m),
                              std::min(scene.camera.height, w[3] + m)};
    }
    const bool shot = request.kind == FrameKind::ShotFrame;
    if (shot && previous.scene) plan.changes = std::make_shared<const SceneChanges>(scene_changes(*previous.scene, scene));
    plan.threads = scene.render.parallel.threads > 0 ? scene.render.parallel.threads : tbb::this_task_arena::max_concurrency();
    const Inputs in{scene, previous, request, shot, plan.changes && plan.changes->comparable, cached, scene.render.cache.light_parts};

    plan.steps.push_back({AccelStep{accel_source(in, plan.changes.get()), rs.lighting}});
    const DeepSource deep = deep_source(in);
    plan.deep_out = !request.deep_out.empty() ? request.deep_out : deep == DeepSource::Trace ? request.deep_out_if_traced : "";
    plan.steps.push_back(
        {VisibilityStep{deep, rs.visibility, deep == DeepSource::ReadFile ? request.deep_in : "", crop, crop || !plan.deep_out.empty()}});

    const CacheStart start = cache_start(in);
    const Gathering g = gathering(in, start);
    std::optional<RadiosityStep> radiosity;
    if (const auto source = radiosity_source(in, g)) {
        radiosity = RadiosityStep{*source, rs.radiosity, rs.radiosity.folder};
        radiosity->settings.light_parts = in.parts;
        // The full frame's, whatever the crop: a crop must light what it sees as the frame does.
        radiosity->settings.pixel_gather_rays = static_cast<double>(scene.camera.width) * scene.camera.height * rs.indirect.rays;
    }
    // A carried radiosity says what light changed, which the records' judgement needs first.
    const bool carried = radiosity && radiosity->source == RadiositySource::Carry;
    if (carried) plan.steps.push_back({*radiosity});
    if (start != CacheStart::None) {
        CacheStartStep c;
        c.start = start;
        c.ao = rs.indirect.ao;
        if (start == CacheStart::File) c.cache_in = request.cache_in;
        c.flush_crop = request.kind == FrameKind::Regather && crop && start != CacheStart::Empty;
        c.force = request.force;
        c.reuse = request.cache_reuse;
        c.light_parts = in.parts;
        plan.steps.push_back({c});
    }
    add_light_steps(plan, in, g, carried ? std::nullopt : radiosity);
    if (radiosity) {
        const bool ranks = request.comm && request.comm->size() > 1;
        plan.steps.push_back(
            {FinishRadiosityStep{ranks && (shot || !scene.render.radiosity.folder.empty()), scene.render.radiosity.folder}});
    }
    refuse_what_cannot_run(scene, plan, request);
    return plan;
}

namespace {

// Each step as JSON: its name and its configuration.
using J = nlohmann::json;
J step_json(const AccelStep& s) { return {{"step", "accel"}, {"from", name(s.source)}}; }
J step_json(const VisibilityStep& s) { return {{"step", "visibility"}, {"from", name(s.source)}, {"crop", s.crop}}; }
J step_json(const RadiosityStep& s) { return {{"step", "radiosity"}, {"from", name(s.source)}}; }
J step_json(const FinishRadiosityStep& s) { return {{"step", "finish radiosity"}, {"share", s.share}, {"save", !s.folder.empty()}}; }
J step_json(const CacheStartStep& s) {
    return {{"step", "cache start"}, {"from", name(s.start)}, {"flush_crop", s.flush_crop}, {"light_parts", s.light_parts}};
}
J step_json(const SpecularSitesStep&) { return {{"step", "specular sites"}}; }
J step_json(const GatherRecordsStep& s) {
    return {{"step", "gather records"},   {"hessian", s.hessian},     {"first_rays", s.first_rays},
            {"own_weight", s.own_weight}, {"keep_hits", s.keep_hits}, {"preview", s.preview}};
}
J step_json(const RefineStep& s) {
    return {{"step", "refine"},
            {"rays", s.rays},
            {"keep_rays", s.keep_rays},
            {"keep_gathers", s.keep_gathers},
            {"refined_before", s.refined_before}};
}
J step_json(const GatherSitesStep& s) { return {{"step", "gather sites"}, {"keep_hits", s.keep_hits}}; }
J step_json(const BruteGatherStep& s) { return {{"step", "brute force"}, {"sites", s.sites}}; }
J step_json(const ShadeStep& s) {
    return {{"step", "shade"},          {"indirect", name(s.indirect)}, {"sites", name(s.sites)}, {"correction_rays", s.correction_rays},
            {"per_light", s.per_light}, {"quick_look", s.quick_look}};
}

}  // namespace

nlohmann::json FramePlan::describe() const {
    nlohmann::json list = nlohmann::json::array();
    for (const PlannedStep& s : steps) {
        nlohmann::json j = std::visit([](const auto& step) { return step_json(step); }, s.step);
        if (s.when == RunWhen::ShadingMissed) j["when"] = "if shading missed";
        list.push_back(std::move(j));
    }
    return {{"frame", frame},     {"window", window},        {"gather_window", gather_window}, {"deep_out", !deep_out.empty()},
            {"threads", threads}, {"steps", std::move(list)}};
}

}  // namespace bounce
