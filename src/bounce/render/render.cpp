#include "bounce/render/render.h"

#include "bounce/gather/guide.h"

#include <fmt/format.h>
#include <sys/resource.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <tbb/task_arena.h>

#include "bounce/accel/accel.h"
#include "bounce/render/distributed.h"
#include "bounce/render/frame.h"
#include "bounce/render/frame_passes.h"
#include "bounce/cache/passes.h"
#include "bounce/core/error.h"
#include "bounce/core/memory.h"
#include "bounce/core/parallel.h"
#include "bounce/gather/gather.h"
#include "bounce/lighting/lighting.h"
#include "bounce/radiosity/radiosity.h"
#include "bounce/scene/params.h"
#include "bounce/shade/layers.h"
#include "bounce/shade/shade.h"

namespace bounce {

void validate_deep_for_scene(const DeepBuffer& deep, const Scene& scene, const std::string& path) {
    if (deep.scene_fingerprint != scene.visibility_fingerprint())
        throw InputError(path, "bounce:scene_fingerprint",
                         "deep file was made for another scene or camera (or dicing of its subdivision surfaces), or a file "
                         "it shows (a mesh, a displacement map) has changed since; re-render visibility without --deep-in");
    // Fragments lie on the scene's surfaces: a position far outside them was written by hand.
    const Bounds reach = scene.visible_bounds();
    const float slack = 0.01f * length(reach.hi - reach.lo) + 1e-6f;
    const auto outside = [&](const Vec3& p) {
        return p.x < reach.lo.x - slack || p.y < reach.lo.y - slack || p.z < reach.lo.z - slack || p.x > reach.hi.x + slack ||
               p.y > reach.hi.y + slack || p.z > reach.hi.z + slack;
    };
    for (size_t i = 0; i < deep.fragments.size(); ++i) {
        const Fragment& f = deep.fragments[i];
        if (const char* bad = invalid_fragment_field(f))
            throw InputError(path, fmt::format("fragment {} channel {}", i, bad), "value out of range");
        if (outside(f.p) || outside(f.p_base))
            throw InputError(path, fmt::format("fragment {}", i), "position outside the scene's surfaces");
        if (f.material >= scene.materials.size() || f.object >= scene.objects.size())
            throw InputError(path, fmt::format("fragment {}", i), "material or object id out of range for this scene");
        if (f.is_hair() && !scene.objects[f.object].fur)
            throw InputError(path, fmt::format("fragment {}", i), "a hair fragment of an object without fur");
        if (!f.is_hair() && f.prim >= scene.objects[f.object].visible_mesh().triangle_count())
            throw InputError(path, fmt::format("fragment {}", i), "triangle id out of range for this scene");
    }
}

double estimate_render_bytes(const Scene& scene) {
    auto w = frame_window(scene);
    const double pixels = static_cast<double>(w[1] - w[0]) * (w[3] - w[2]);
    // About 1.3 fragments per pixel (edges), the deep buffer's offsets, ~24 float channels of
    // image layers, and per-fragment indirect light and direct radiance.
    const double per_fragment = sizeof(Fragment) + sizeof(Indirect) + sizeof(Color);
    return pixels * (1.3 * per_fragment + sizeof(uint32_t) + 24 * sizeof(float));
}

namespace {

/// The scene loader's dicing of subdivision surfaces and growing of fur, as phases with their sizes.
void report_dicing(const Scene& scene, Stats& stats) {
    double seconds = 0, micropolygons = 0, ray_triangles = 0;
    int level = 0;
    for (const Object& o : scene.objects) {
        if (o.dicing_level == 0) continue;
        seconds += o.dicing_seconds;
        micropolygons += static_cast<double>(o.visible().triangle_count());
        ray_triangles += static_cast<double>(o.coarse.triangle_count());
        level = std::max(level, o.dicing_level);
    }
    double fur_seconds = 0, strands = 0, segments = 0, fur_bytes = 0;
    for (const Object& o : scene.objects)
        if (o.fur) {
            fur_seconds += o.fur->seconds;
            strands += static_cast<double>(o.fur->strand_count());
            segments += static_cast<double>(o.fur->segment_count());
            fur_bytes += static_cast<double>(o.fur->memory_bytes());
        }
    if (strands > 0) {
        stats.add_phase("fur", fur_seconds);
        stats.set("fur_strands", strands);
        stats.set("fur_segments", segments);
        stats.set("fur_bytes", fur_bytes);
    }
    if (level == 0) return;
    stats.add_phase("dicing", seconds);
    stats.set("dicing_level", level);
    stats.set("micropolygons", micropolygons);
    stats.set("ray_triangles", ray_triangles);
}

/// Instances: how many placements, of how many prototypes, place how many triangles (what a
/// flat scene would have held; the BVHs hold only the prototypes').
void report_instances(const Scene& scene, Stats& stats) {
    double instances = 0, prototypes = 0, placed = 0;
    for (const Object& o : scene.objects) {
        prototypes += o.prototype ? 1 : 0;
        if (!o.instance) continue;
        ++instances;
        placed += static_cast<double>(o.coarse_mesh().triangle_count());
    }
    if (instances == 0) return;
    stats.set("instances", instances);
    stats.set("prototypes", prototypes);
    stats.set("instanced_triangles", placed);
}

/// Forwards progress to the caller's sink (if any) and carries the request's cancel token.
class CancellableSink : public ProgressSink {
  public:
    CancellableSink(ProgressSink* inner, const CancelToken* token) : inner_(inner) { cancel = token; }
    void update(const std::string& name, uint64_t done, uint64_t total, double elapsed) override {
        if (inner_) inner_->update(name, done, total, elapsed);
    }
    void finish(const std::string& name, uint64_t total, double elapsed) override {
        if (inner_) inner_->finish(name, total, elapsed);
    }

  private:
    ProgressSink* inner_;
};

void set_metadata(Image& image, const Scene& scene, const DeepBuffer& deep, Stats& stats) {
    auto& md = image.metadata;
    md["scene"] = scene.path;
    const nlohmann::json params = param_values(scene, ~0u);
    for (const auto& [key, value] : params.items()) md[key] = value.is_string() ? value.get<std::string>() : value.dump();
    md["deep_seed"] = std::to_string(deep.seed);
    md["deep_spp"] = std::to_string(deep.spp);
    md["scene_fingerprint"] = fmt::format("{:016x}", deep.scene_fingerprint);
    md["render_time_s"] = fmt::format("{:.3f}", stats.to_json()["total_s"].get<double>());
}

}  // namespace

Image paste_over(const Image& base, const Image& window, const std::string& base_name) {
    if (base.full_width != window.full_width || base.full_height != window.full_height || base.x0 != 0 || base.y0 != 0 ||
        base.width != base.full_width || base.height != base.full_height)
        throw InputError(base_name, "",
                         fmt::format("base image is {}x{} (window {}x{} at {},{}); the render is a {}x{} frame", base.full_width,
                                     base.full_height, base.width, base.height, base.x0, base.y0, window.full_width, window.full_height));
    Image out = base;
    out.metadata = window.metadata;
    for (const Layer& l : window.layers) {
        Layer* dst = out.find(l.name);
        if (!dst || dst->channels != l.channels)
            throw InputError(base_name, l.name, "base image lacks this layer (render it with the same settings)");
        const size_t nc = l.channels.size();
        for (int y = 0; y < window.height; ++y)
            std::copy_n(&l.data[static_cast<size_t>(y) * window.width * nc], static_cast<size_t>(window.width) * nc,
                        &dst->data[((static_cast<size_t>(y + window.y0)) * out.width + window.x0) * nc]);
    }
    return out;
}

namespace {

/// Under MPI each rank bakes the sides its own gathers hit. They are exchanged only when they
/// outlive the frame: saved by rank 0, or carried to a shot's next frame, whose list of changed
/// sides (temporal.h) must be the same on every rank. Values are the same wherever baked.
void finish_radiosity(const FrameContext& ctx, const FramePlan& plan, RadiosityTextures& rt, size_t baked_before) {
    if (plan.share_radiosity) share_radiosity_pass(ctx, rt);
    save_radiosity_pass(ctx, rt, baked_before);
}

/// The cache, gathering and shading passes of a cache render: the plan's gathering, or for a
/// re-shade (GatherStep::WhereMissing) shading first and gathering only where records miss.
/// `radiosity` is the frame's when the plan carried it; else it is made when a gather runs.
void run_cache_passes(const FrameContext& ctx, const FramePlan& plan, const VisibilityResult& deep, const FrameState& previous,
                      RadiosityResult& radiosity, CacheStartResult& start, const RenderRequest& request, RenderResult& result) {
    size_t baked_before = 0;
    const SpecularSitesResult specular = specular_sites_pass(ctx, plan, deep.shaded());
    if (specular.mirrors && !radiosity.textures && ctx.scene.render.shading.indirect_at_specular_hits == SpecularHitLight::Radiosity)
        radiosity = radiosity_pass(ctx, plan, previous);
    auto gather = [&] {
        if (!radiosity.textures) radiosity = radiosity_pass(ctx, plan, previous);
        baked_before = radiosity.textures ? radiosity.textures->baked_sides() : 0;
        PhaseTimer t(ctx.stats, "gather");
        const uint64_t rays_before = ctx.stats.total().gather_rays;
        GatherPassResult g =
            cache_gather_pass(ctx, plan, deep, radiosity.textures.get(), *start.cache, std::move(start.judged), request.preview, specular);
        const double secs = t.stop();
        const uint64_t rays = ctx.stats.total().gather_rays - rays_before;
        ctx.stats.set("gather_rays_per_s", secs > 0 ? static_cast<double>(rays) / secs : 0.0);
        result.records_new += g.records_new;
        result.fragment_records_new += g.fragment_records_new;
        result.temporal.regathered = g.regathered, result.temporal.reshaded = g.reshaded;
        result.waiting = std::move(g.waiting);
        result.gathers = std::move(g.gathers);
        result.gathered = true;
    };
    const auto quick_look = plan.preview ? request.preview : std::function<void(const Image&)>();
    ShadeResult shaded;
    if (plan.gather == GatherStep::WhereMissing) {
        shaded = shading_pass(ctx, deep.shaded(), start.cache.get(), nullptr, specular, radiosity.textures.get(), quick_look);
        if (shaded.shading_misses > 0) {
            gather();
            shaded = shading_pass(ctx, deep.shaded(), start.cache.get(), nullptr, specular, radiosity.textures.get());
        }
    } else {
        gather();
        shaded = shading_pass(ctx, deep.shaded(), start.cache.get(), nullptr, specular, radiosity.textures.get());
    }
    result.shading_misses = shaded.shading_misses;
    result.image = std::move(shaded.image);
    result.deep_colour = std::move(shaded.colours);
    const IrradianceCache& cache = *start.cache;
    ctx.stats.set("records", static_cast<double>(cache.size()));
    ctx.stats.set("records_loaded", static_cast<double>(result.records_loaded));
    ctx.stats.set("records_new", static_cast<double>(result.records_new));
    // After the shading pass: refined fragments' gathers may have baked sides too.
    if (radiosity.textures) finish_radiosity(ctx, plan, *radiosity.textures, baked_before);
    if ((plan.refine || cache.fragment_record_count() > 0) && !shaded.refined.empty())  // empty: a rank that writes no image
        add_mask_layer(result.image, shaded.refined, "refined");
}

/// Brute force, direct light only, or a cache file read for its records layer.
void run_direct_or_brute(const FrameContext& ctx, const FramePlan& plan, const VisibilityResult& deep, const FrameState& previous,
                         RadiosityResult& radiosity, RenderResult& result) {
    std::vector<Indirect> light;
    SpecularSitesResult specular = specular_sites_pass(ctx, plan, deep.shaded());
    const bool radiosity_sites = ctx.scene.render.shading.indirect_at_specular_hits == SpecularHitLight::Radiosity;
    if (specular.mirrors && radiosity_sites && !radiosity.textures && ctx.scene.render.indirect.any())
        radiosity = radiosity_pass(ctx, plan, previous);
    if (plan.gather == GatherStep::Brute) {
        if (!radiosity.textures) radiosity = radiosity_pass(ctx, plan, previous);
        const size_t baked_before = radiosity.textures ? radiosity.textures->baked_sides() : 0;
        PhaseTimer t(ctx.stats, "gather");
        const uint64_t rays_before = ctx.stats.total().gather_rays;
        light = brute_gather_pass(ctx, deep.shaded(), radiosity.textures.get(), specular);
        const double secs = t.stop();
        const uint64_t rays = ctx.stats.total().gather_rays - rays_before;
        ctx.stats.set("gather_rays_per_s", secs > 0 ? static_cast<double>(rays) / secs : 0.0);
        result.gathered = true;
        if (radiosity.textures) finish_radiosity(ctx, plan, *radiosity.textures, baked_before);
    }
    ShadeResult shaded =
        shading_pass(ctx, deep.shaded(), nullptr, plan.gather == GatherStep::Brute ? &light : nullptr, specular, radiosity.textures.get());
    result.image = std::move(shaded.image);
    result.deep_colour = std::move(shaded.colours);
    if (result.cache) {
        ctx.stats.set("records", static_cast<double>(result.cache->size()));
        ctx.stats.set("records_loaded", static_cast<double>(result.records_loaded));
    }
}

/// The temporal counts of a frame of a shot, in stats.
void report_temporal(const RenderResult& r, Stats& stats) {
    const TemporalCounts& t = r.temporal;
    stats.set("records_kept", static_cast<double>(t.kept));
    stats.set("records_moved", static_cast<double>(t.moved));
    stats.set("records_regathered", static_cast<double>(t.regathered));
    stats.set("records_reshaded", static_cast<double>(t.reshaded));
    stats.set("records_dropped_temporal", static_cast<double>(t.dropped));
    stats.set("records_waiting", static_cast<double>(r.waiting.size()));
    stats.set("records_anchored", static_cast<double>(t.anchored));
    stats.set("records_anchor_kept", static_cast<double>(t.anchors_kept));
}

}  // namespace

FrameState RenderResult::release_state() {
    FrameState s;
    s.deep = std::make_shared<const DeepBuffer>(std::move(deep));
    s.cache = std::shared_ptr<const IrradianceCache>(std::move(cache));
    s.accel = std::move(accel);
    s.radiosity = std::move(radiosity);
    s.waiting = std::make_shared<const std::vector<Record>>(std::move(waiting));
    s.gathers = std::make_shared<const std::vector<Record>>(std::move(gathers));
    return s;
}

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

/// A frame spread over an MPI job: what every rank traced and what the exchanges cost, in
/// the stats of each (rank 0's are written). `sent0`, `wait0`: the communicator's totals
/// when the frame began.
void report_ranks(Communicator& comm, Stats& stats, uint64_t sent0, double wait0) {
    struct Mine {
        Counters counters;
        uint64_t sent;
        double wait_s;
    } mine{stats.total(), comm.bytes_sent - sent0, comm.wait_s - wait0};
    const std::vector<std::string> all = comm.allgather(std::string(reinterpret_cast<const char*>(&mine), sizeof(mine)));
    Counters sum;
    uint64_t sent = 0;
    nlohmann::json waits = nlohmann::json::array();
    for (const std::string& b : all) {
        Mine theirs;
        std::memcpy(&theirs, b.data(), sizeof(theirs));
        sum += theirs.counters, sent += theirs.sent;
        waits.push_back(theirs.wait_s);
    }
    stats.set("ranks", comm.size());
    stats.set("gather_rays_all_ranks", static_cast<double>(sum.gather_rays));
    stats.set("shadow_rays_all_ranks", static_cast<double>(sum.shadow_rays));
    // Radiosity texels are baked by each rank's own gathers: a texel two ranks need is baked twice.
    stats.set("radiosity_bake_cpu_s_all_ranks", static_cast<double>(sum.radiosity_bake_ns) * 1e-9);
    stats.set("exchange_bytes", static_cast<double>(sent));
    stats.set("exchange_s_per_rank", std::move(waits));  // waiting for the slowest rank, and the transfer
}

}  // namespace

RenderResult run_frame(const Scene& scene, const FramePlan& plan, const FrameState& previous, const RenderRequest& request, Stats& stats,
                       ProgressSink* progress) {
    const uint64_t sent0 = request.comm ? request.comm->bytes_sent : 0;
    const double wait0 = request.comm ? request.comm->wait_s : 0;
    tbb::task_arena arena(plan.threads);
    stats.set("threads", plan.threads);
    report_dicing(scene, stats);
    report_instances(scene, stats);
    CancellableSink sink(progress, request.cancel);
    ProgressSink* const ps = progress || request.cancel ? &sink : nullptr;
    RenderResult result;
    result.plan = plan;
    arena.execute([&] {
        if (plan.accel == AccelStep::Keep) {
            result.accel = previous.accel;
        } else {
            PhaseTimer t(stats, "build BVH");
            result.accel = std::make_shared<const SceneAccel>(scene, plan.accel == AccelStep::Update ? previous.accel.get() : nullptr);
        }
        const SceneAccel& accel = *result.accel;
        if (const BvhReuse r = accel.reuse(); r.kept + r.refit + r.built > 0)
            stats.set("bvh_parts", nlohmann::json{{"kept", r.kept}, {"refit", r.refit}, {"built", r.built}});
        stats.set("ray_offset", accel.ray_offset());
        Materials materials(scene);
        DirectLighting lighting(scene, accel);
        SingleProcess alone;
        const FrameContext ctx{scene, accel, materials, lighting, stats, ps, request.cancel, request.comm ? *request.comm : alone};
        VisibilityResult deep = visibility_pass(ctx, plan, previous);
        // A carried radiosity says what light changed, which the records' judgement needs first.
        RadiosityResult radiosity;
        if (plan.radiosity == RadiosityStep::Carry) radiosity = radiosity_pass(ctx, plan, previous);
        CacheStartResult start = cache_start_pass(ctx, plan, previous, radiosity);
        result.records_loaded = start.records_loaded;
        result.cache_differences = start.differences;
        result.cache_other_lighting = start.other_lighting;
        if (start.other_lighting) stats.set("cache_bounce_light_stale", 1);
        const TemporalJudgement& j = start.judged;
        result.temporal = {j.kept, j.moved, j.view, j.light, j.dropped, 0, 0, j.anchored, j.anchors_kept};
        if (!start.differences.empty()) stats.set("cache_reused_with_other_settings", nlohmann::json(start.differences));
        result.cache_info = cache_file_info(scene, plan.frame);
        if (plan.gather == GatherStep::Cache || plan.gather == GatherStep::WhereMissing) {
            run_cache_passes(ctx, plan, deep, previous, radiosity, start, request, result);
        } else {
            result.cache = std::move(start.cache);
            run_direct_or_brute(ctx, plan, deep, previous, radiosity, result);
        }
        if (!result.cache) result.cache = std::move(start.cache);
        if (result.cache) {
            std::vector<Vec3> positions;
            for (size_t i = 0; i < result.cache->size(); ++i) positions.push_back(result.cache->record(i).p);
            add_records_layer(result.image, scene.camera, positions);
        }
        // Sources of a lazy bake point at this frame's materials and lights: only a shot's next
        // frame takes the textures (RadiosityTextures::carry points them at its own).
        result.radiosity = std::move(radiosity.textures);
        if (!plan.deep_out.empty()) {
            result.deep_colour = scene.render.shading.deep_colour ? colours_of_window(deep, result.deep_colour) : std::vector<Color>();
            result.gathered_deep = std::make_shared<const DeepBuffer>(deep.crop ? std::move(deep.gathered) : deep.gathered);
        } else {
            result.deep_colour.clear();
        }
        // The passes are done with the fragments: moved, not copied (a Sponza frame's are 100 MB).
        result.deep = deep.crop ? std::move(*deep.crop) : std::move(deep.gathered);
    });
    if (request.comm && request.comm->size() > 1) report_ranks(*request.comm, stats, sent0, wait0);
    if (plan.cache == CacheStart::Temporal) report_temporal(result, stats);
    stats.set("pixels", static_cast<double>(result.deep.pixel_count()));
    if (result.deep.pixel_count() > 0)
        stats.set("gather_rays_per_pixel", static_cast<double>(stats.total().gather_rays) / static_cast<double>(result.deep.pixel_count()));
    stats.set("plan", plan.describe());
    set_metadata(result.image, scene, result.deep, stats);
    return result;
}

RenderResult render(const Scene& scene, const RenderRequest& request, Stats& stats, ProgressSink* progress) {
    const FrameState none;
    RenderResult r = run_frame(scene, plan_frame(scene, none, request), none, request, stats, progress);
    FrameFiles files;
    files.deep_out = r.plan.deep_out;
    write_frame_outputs(r, files, "", stats);
    return r;
}

}  // namespace bounce
