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
#include "bounce/render/frame_steps.h"
#include "bounce/cache/passes.h"
#include "bounce/core/error.h"
#include "bounce/core/memory.h"
#include "bounce/core/parallel.h"
#include "bounce/gather/gather.h"
#include "bounce/lighting/lighting.h"
#include "bounce/radiosity/radiosity.h"
#include "bounce/config/params.h"
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

double estimate_render_bytes(const std::array<int, 4>& w) {
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
    arena.execute([&] {
        FrameRun run(scene, plan, previous, request, stats, ps);
        for (const PlannedStep& step : plan.steps) run.run(step);
        result = run.finish();
    });
    if (request.comm && request.comm->size() > 1) report_ranks(*request.comm, stats, sent0, wait0);
    if (plan.cache_start() == CacheStart::Temporal) report_temporal(result, stats);
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
