// Microbenchmarks (issue #8), Google Benchmark: cache lookups with 10^3..10^6 records, one
// record's metric and weight, one hemisphere gather, the same gather rays through raw Embree
// (rtcIntersect1 on the coarse BVH) and through bounce's offsetting trace, and reading a deep
// file. The ray benchmarks use the scene in BOUNCE_BENCH_SCENE (default: the Cornell box) at
// the visible points of a small primary-visibility pass; rates are items_per_second (rays/s).
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <filesystem>
#include <memory>

#include "bounce/cache/irradiance_cache.h"
#include "bounce/core/sampling.h"
#include "bounce/gather/gather.h"
#include "bounce/radiosity/radiosity.h"
#include "bounce/render/render.h"
#include "bounce/scene/scene_load.h"

namespace bounce {
namespace {

/// A cache of n records on a 1000 x 1000 plane (y = 0), spaced on a jittered grid with radii of
/// twice the spacing, so a lookup sees about a dozen candidates whatever n.
IrradianceCache plane_cache(size_t n) {
    CacheSettings s;
    s.neighbour_clamp = false;
    s.gradient_limit = 0;
    Bounds b;
    b.extend({-1, -1, -1});
    b.extend({1001, 1, 1001});
    IrradianceCache cache(b, s, false);
    const auto side = static_cast<size_t>(std::ceil(std::sqrt(static_cast<double>(n))));
    const float step = 1000.0f / static_cast<float>(side);
    RandomStream rng(5, 6);
    for (size_t i = 0; i < n; ++i) {
        Record r;
        r.p = {(static_cast<float>(i % side) + rng.get(i, 0)) * step, 0, (static_cast<float>(i / side) + rng.get(i, 1)) * step};
        r.n = {0, 1, 0};
        r.E = Color(1 + rng.get(i, 2));
        r.footprint = step / 4;
        r.radius = r.raw_radius = 2 * step;
        r.key = i;
        cache.insert_loaded(r);
    }
    return cache;
}

void BM_CacheLookup(benchmark::State& state) {
    IrradianceCache cache = plane_cache(static_cast<size_t>(state.range(0)));
    RandomStream rng(7, 8);
    uint64_t i = 0;
    int contributions = 0;
    for (auto _ : state) {
        Interpolated in = cache.lookup({rng.get(i, 0) * 1000, 0, rng.get(i, 1) * 1000}, {0, 1, 0});
        contributions += in.records;
        benchmark::DoNotOptimize(in);
        ++i;
    }
    state.SetItemsProcessed(static_cast<int64_t>(state.iterations()));
    state.counters["records_per_lookup"] = static_cast<double>(contributions) / static_cast<double>(state.iterations());
    state.counters["bytes_per_record"] = static_cast<double>(cache.memory_bytes()) / static_cast<double>(cache.size());
}
BENCHMARK(BM_CacheLookup)->RangeMultiplier(10)->Range(1000, 1000000)->Unit(benchmark::kNanosecond);

void BM_RecordWeight(benchmark::State& state) {
    Record r;
    r.p = {0, 0, 0};
    r.n = {0, 1, 0};
    r.radius = r.raw_radius = 1;
    r.E = Color(1);
    r.grad_t = {Vec3(0.1f), Vec3(0.1f), Vec3(0.1f)};
    r.weber = 2;
    const RecordMetric s{CacheSettings{}};
    RandomStream rng(9, 10);
    uint64_t i = 0;
    for (auto _ : state) {
        Vec3 p(rng.get(i, 0) - 0.5f, 0, rng.get(i, 1) - 0.5f), n = normalize(Vec3(rng.get(i, 2) * 0.1f, 1, 0));
        benchmark::DoNotOptimize(record_weight(r, p, n, s));
        ++i;
    }
    state.SetItemsProcessed(static_cast<int64_t>(state.iterations()));
}
BENCHMARK(BM_RecordWeight);

/// The scene of the ray benchmarks, its BVHs, radiosity textures and some visible points.
struct RayRig {
    Scene scene;
    std::unique_ptr<SceneAccel> accel;
    std::unique_ptr<Materials> materials;
    std::unique_ptr<DirectLighting> lighting;
    std::unique_ptr<RadiosityTextures> radiosity;
    std::vector<Fragment> points;
    static RayRig& get() {
        static RayRig rig;
        return rig;
    }

  private:
    RayRig() {
        const char* env = std::getenv("BOUNCE_BENCH_SCENE");
        std::string path = env ? env : std::string(BOUNCE_SOURCE_DIR) + "/scenes/cornell/cornell.json";
        scene = load_scene(path, {"camera.resolution=[64,36]", "render.spp=1"});
        accel = std::make_unique<SceneAccel>(scene, scene.render.lighting);
        materials = std::make_unique<Materials>(scene);
        lighting = std::make_unique<DirectLighting>(scene, *accel, scene.render.lighting);
        Stats stats;
        radiosity = std::make_unique<RadiosityTextures>(
            RadiosityTextures::bake(scene, *materials, *lighting, scene.render.radiosity, stats, nullptr));
        DeepBuffer deep = render_visibility(scene, *accel, scene.render.visibility, stats, nullptr);
        points = deep.fragments;
    }
};

constexpr int kRaysPerPoint = 2048;                   // as HemisphereGather/2048: like for like
const int kRays = gather_grid(kRaysPerPoint).rays();  // the grid rounds: m * n rays

/// The gather's directions at point i, in the gather's own order (rows of its stratified
/// elevation x azimuth grid, cosine-weighted): the raw baselines trace exactly what a gather
/// of kRaysPerPoint rays traces.
template <typename Fn>
void for_each_gather_ray(const Fragment& f, uint64_t i, Fn&& fn) {
    const Frame frame(f.n_base);
    const GatherGrid grid = gather_grid(kRaysPerPoint);
    RandomStream rng(11, i);
    for (int j = 0; j < grid.m; ++j)
        for (int k = 0; k < grid.n; ++k) {
            const auto c = static_cast<uint64_t>(j * grid.n + k);
            fn(f.p, frame.to_world(gather_cell_direction(grid, j, k, rng.get(c, 0), rng.get(c, 1))));
        }
}

void BM_RaysRawEmbree(benchmark::State& state) {
    RayRig& rig = RayRig::get();
    const float eps = rig.accel->ray_offset();
    uint64_t i = 0, hits = 0;
    for (auto _ : state) {
        const Fragment& f = rig.points[i % rig.points.size()];
        for_each_gather_ray(f, i,
                            [&](const Vec3& p, const Vec3& d) { hits += rig.accel->coarse().intersect(p, d, eps, INFINITY).valid(); });
        ++i;
    }
    benchmark::DoNotOptimize(hits);
    state.SetItemsProcessed(static_cast<int64_t>(state.iterations()) * kRays);
}
BENCHMARK(BM_RaysRawEmbree)->Unit(benchmark::kMicrosecond);

/// The same rays through rtcIntersect16 in the gather's packet order (what the gather does).
void BM_RaysRawEmbreePackets(benchmark::State& state) {
    RayRig& rig = RayRig::get();
    const float eps = rig.accel->ray_offset();
    const GatherGrid grid = gather_grid(kRaysPerPoint);
    const auto n = static_cast<size_t>(kRays);
    std::vector<Vec3> dirs(n), packed(n);
    std::vector<Hit> out(n);
    const std::vector<uint32_t> order = gather_packet_order(grid);
    uint64_t i = 0, hits = 0;
    for (auto _ : state) {
        const Fragment& f = rig.points[i % rig.points.size()];
        size_t k = 0;
        for_each_gather_ray(f, i, [&](const Vec3&, const Vec3& d) { dirs[k++] = d; });
        for (size_t r = 0; r < order.size(); ++r) packed[r] = dirs[order[r]];  // the gather's packets
        rig.accel->coarse().intersect_from(f.p, packed.data(), packed.size(), eps, out.data());
        for (const Hit& h : out) hits += h.valid();
        ++i;
    }
    benchmark::DoNotOptimize(hits);
    state.SetItemsProcessed(static_cast<int64_t>(state.iterations()) * kRays);
}
BENCHMARK(BM_RaysRawEmbreePackets)->Unit(benchmark::kMicrosecond);

void BM_RaysOffsetTrace(benchmark::State& state) {
    RayRig& rig = RayRig::get();
    uint64_t i = 0, hits = 0;
    for (auto _ : state) {
        const Fragment& f = rig.points[i % rig.points.size()];
        for_each_gather_ray(f, i, [&](const Vec3& p, const Vec3& d) { hits += rig.accel->trace(p, d).valid(); });
        ++i;
    }
    benchmark::DoNotOptimize(hits);
    state.SetItemsProcessed(static_cast<int64_t>(state.iterations()) * kRays);
}
BENCHMARK(BM_RaysOffsetTrace)->Unit(benchmark::kMicrosecond);

void BM_HemisphereGather(benchmark::State& state) {
    RayRig& rig = RayRig::get();
    GatherSettings gs = plan_frame(rig.scene, FrameState{}, RenderRequest{}).gather;
    gs.rays = static_cast<int>(state.range(0));
    Gatherer g(rig.scene, *rig.accel, *rig.materials, *rig.lighting, rig.radiosity.get(), gs);
    Counters c;
    uint64_t i = 0;
    for (auto _ : state) {
        const Fragment& f = rig.points[i % rig.points.size()];
        benchmark::DoNotOptimize(g.gather(f.p, f.n_base, RandomStream(12, i), c));
        ++i;
    }
    state.SetItemsProcessed(static_cast<int64_t>(c.gather_rays));
}
BENCHMARK(BM_HemisphereGather)->Arg(512)->Arg(2048)->Unit(benchmark::kMicrosecond);

/// Whole gather phases (issue 64): the cache's record gathers (its gathering pass and
/// refinement) at 64 rays per record against brute force at 64 rays per pixel, with the same
/// scene, deep buffer and thread, GI and AO, at 256x256. Timed over the gather phase alone
/// (visibility and the radiosity bake left out); items are gather rays, so items_per_second
/// is each method's gather rays/s and the cache's per-record work shows as their ratio.
void BM_GatherPhase(benchmark::State& state) {
    const bool cache = state.range(0) == 1, ao = state.range(1) == 1;
    RayRig& rig = RayRig::get();
    const Scene s =
        load_scene(rig.scene.path, {"camera.resolution=[256,256]", "render.spp=4", "render.rays=64", "render.threads=1",
                                    cache ? "render.gi=\"cache\"" : "render.gi=\"brute\"", ao ? "render.ao=true" : "render.ao=false"});
    double rays = 0;
    for (auto _ : state) {
        Stats stats;
        benchmark::DoNotOptimize(render(s, {}, stats, nullptr));
        const auto j = stats.to_json();
        state.SetIterationTime(j["phases_s"]["gather"].get<double>());
        rays += static_cast<double>(j["rays"]["gather"].get<uint64_t>());
    }
    state.SetItemsProcessed(static_cast<int64_t>(rays));
    state.SetLabel(std::string(cache ? "cache, 64 rays per record" : "brute force, 64 rays") + (ao ? ", ao" : ", gi"));
}
BENCHMARK(BM_GatherPhase)->ArgNames({"cache", "ao"})->ArgsProduct({{0, 1}, {0, 1}})->UseManualTime()->Unit(benchmark::kMillisecond);

void BM_DeepRead(benchmark::State& state) {
    RayRig& rig = RayRig::get();
    const std::string path = (std::filesystem::temp_directory_path() / "bounce-bench-deep.exr").string();
    Stats stats;
    Scene s = load_scene(rig.scene.path, {"camera.resolution=[256,256]", "render.spp=4"});
    DeepBuffer deep = render_visibility(s, *rig.accel, s.render.visibility, stats, nullptr);
    write_deep(path, deep);
    for (auto _ : state) benchmark::DoNotOptimize(read_deep(path));
    const double pixels = static_cast<double>(deep.pixel_count());
    state.counters["file_bytes_per_pixel"] = static_cast<double>(std::filesystem::file_size(path)) / pixels;
    state.counters["memory_bytes_per_pixel"] =
        static_cast<double>(deep.fragments.size() * sizeof(Fragment) + deep.offsets.size() * sizeof(deep.offsets[0])) / pixels;
    state.counters["fragments_per_pixel"] = static_cast<double>(deep.fragments.size()) / pixels;
    state.SetItemsProcessed(static_cast<int64_t>(state.iterations()) * static_cast<int64_t>(pixels));
    std::filesystem::remove(path);
}
BENCHMARK(BM_DeepRead)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace bounce

BENCHMARK_MAIN();
