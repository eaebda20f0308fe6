// Issue 49's load and build rates: a scene's load (bounce's loader: parsing, mesh files through
// Assimp, tessellation) and its ray-tracing structures (SceneAccel: BVHs and the ray-offset
// measurement) against the physical limits on the same triangles, with the mesh files parsed and
// read from a mesh cache (scene/mesh_cache.h): Embree's own build of them
// (shared buffers, no copies, one scene per prototype placed by instances as bounce does) at
// each build quality, and reading the scene's mesh files from the page cache. Prints one
// Markdown row per scene (docs/benchmarks.md, "Load and build rates").
//
//   bounce_build_rate SCENE... [--repeat N]
//   bounce_build_rate --once SCENE      (one of each in a fresh process; BOUNCE_MESH_CACHE as set)
#include <embree3/rtcore.h>
#include <fmt/format.h>
#include <malloc.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <string>
#include <unistd.h>
#include <vector>

#include "frontend/environment.h"
#include "bounce/accel/accel.h"
#include "bounce/core/parallel.h"
#include "bounce/scene/scene_load.h"

namespace bounce {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

/// Best of `repeat` runs of `f` (seconds).
template <typename F>
double best_of(int repeat, F&& f) {
    double best = 1e30;
    for (int i = 0; i < repeat; ++i) {
        const auto t0 = Clock::now();
        f();
        best = std::min(best, seconds_since(t0));
    }
    return best;
}

/// `mesh` as a triangle geometry of `scene` sharing its buffers (nothing copied).
void attach(RTCDevice device, RTCScene scene, const TriangleMesh& mesh) {
    if (mesh.indices.empty()) return;
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    // Embree reads 16 bytes at the last vertex; positions are 12-byte Vec3s, so a padded copy
    // would be needed for the very last one: vectors of Vec3 keep capacity >= size here, and
    // the read of 4 bytes past the end lands in the allocation's slack (as Embree's own samples do).
    rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, mesh.positions.data(), 0, sizeof(Vec3),
                               mesh.positions.size());
    rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, mesh.indices.data(), 0, 3 * sizeof(uint32_t),
                               mesh.triangle_count());
    rtcCommitGeometry(g);
    rtcAttachGeometry(scene, g);
    rtcReleaseGeometry(g);
}

/// Embree alone on the scene's traced triangles: placed objects in one scene, each prototype in
/// its own, placed by one instance per placement. Returns the seconds of every commit.
double raw_build(RTCDevice device, const Scene& scene, RTCBuildQuality quality, bool fine) {
    const auto t0 = Clock::now();
    RTCScene top = rtcNewScene(device);
    rtcSetSceneBuildQuality(top, quality);
    rtcSetSceneFlags(top, RTC_SCENE_FLAG_ROBUST);  // as bounce builds (watertight hits; no spatial splits)
    std::map<const TriangleMesh*, RTCScene> prototypes;
    for (const Object& o : scene.objects) {
        if (!o.placed()) continue;
        const TriangleMesh& mesh = fine ? o.visible_mesh() : o.coarse_mesh();
        if (!o.instance) {
            attach(device, top, mesh);
            continue;
        }
        RTCScene& proto = prototypes[&mesh];
        if (!proto) {
            proto = rtcNewScene(device);
            rtcSetSceneBuildQuality(proto, quality);
            rtcSetSceneFlags(proto, RTC_SCENE_FLAG_ROBUST);
            attach(device, proto, mesh);
            rtcCommitScene(proto);
        }
        RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_INSTANCE);
        rtcSetGeometryInstancedScene(g, proto);
        rtcSetGeometryTransform(g, 0, RTC_FORMAT_FLOAT3X4_ROW_MAJOR, o.placement.m.data());
        rtcCommitGeometry(g);
        rtcAttachGeometry(top, g);
        rtcReleaseGeometry(g);
    }
    rtcCommitScene(top);
    const double s = seconds_since(t0);
    rtcReleaseScene(top);
    for (auto& [mesh, proto] : prototypes) rtcReleaseScene(proto);
    return s;
}

/// Bytes of the files `scene` read (meshes, textures), and the best time to read them whole.
std::pair<double, double> read_rate(const Scene& scene, int repeat) {
    std::vector<std::string> files;
    for (const std::string& path : scene.input_paths())
        if (std::filesystem::is_regular_file(path)) files.push_back(path);
    double bytes = 0;
    for (const auto& f : files) bytes += static_cast<double>(std::filesystem::file_size(f));
    std::vector<char> buffer(1 << 20);
    const double s = best_of(repeat, [&] {
        for (const auto& f : files) {
            std::ifstream in(f, std::ios::binary);
            while (in.read(buffer.data(), static_cast<std::streamsize>(buffer.size())) || in.gcount() > 0) {}
        }
    });
    return {bytes, s};
}

/// Best load of `path` with its mesh files parsed, and with them read from a mesh cache
/// (scene/mesh_cache.h; a fresh folder, filled by one load first).
std::pair<double, double> load_rates(const std::string& path, int repeat, Scene& scene) {
    LoadOptions options = load_options_from_environment();
    options.resources.mesh_cache.reset();
    const double parsed = best_of(repeat, [&] { scene = load_scene(path, {}, options); });
    const auto folder = std::filesystem::temp_directory_path() / fmt::format("bounce-build-rate-{}", getpid());
    options.resources.mesh_cache = std::make_shared<MeshCache>(folder.string(), options.resources.hashes);
    scene = load_scene(path, {}, options);
    const double cached = best_of(repeat, [&] { scene = load_scene(path, {}, options); });
    std::filesystem::remove_all(folder);
    return {parsed, cached};
}

void measure(const std::string& path, int repeat) {
    Scene scene;
    const auto [load, cached] = load_rates(path, repeat, scene);
    double triangles = 0, placed = 0;
    std::set<const TriangleMesh*> unique;
    for (const Object& o : scene.objects) {
        if (!o.placed()) continue;
        placed += static_cast<double>(o.coarse_mesh().triangle_count());
        if (unique.insert(&o.coarse_mesh()).second) triangles += static_cast<double>(o.coarse_mesh().triangle_count());
    }
    const double accel = best_of(repeat, [&] { SceneAccel a(scene, scene.render.lighting); });
    RTCDevice device = rtcNewDevice("threads=0");
    double raw[3];
    const RTCBuildQuality qualities[3] = {RTC_BUILD_QUALITY_LOW, RTC_BUILD_QUALITY_MEDIUM, RTC_BUILD_QUALITY_HIGH};
    bool fine = false;
    for (const Object& o : scene.objects) fine = fine || (o.placed() && o.has_fine());
    for (int q = 0; q < 3; ++q)
        raw[q] = best_of(repeat, [&] { raw_build(device, scene, qualities[q], false); }) +
                 (fine ? best_of(repeat, [&] { raw_build(device, scene, qualities[q], true); }) : 0.0);
    rtcReleaseDevice(device);
    const auto [bytes, read] = read_rate(scene, repeat);
    std::printf("| %s | %.3g | %.3g | %.3f s | %.3f s | %.3f s | %.3f / %.3f / %.3f s | %.1fx | %.1fx | %.1fx | %.0f MB in %.3f s |\n",
                std::filesystem::path(path).filename().c_str(), triangles, placed, load, cached, accel, raw[0], raw[1], raw[2],
                accel / raw[2], (load + accel) / raw[2], (cached + accel) / raw[2], bytes / 1e6, read);
    std::fflush(stdout);
}

/// One load, one SceneAccel and one raw build (high quality) of `path` in a fresh process (the
/// thread pool and Embree's device started first): what a render's first load costs, page
/// faults and all, against Embree's first build.
void measure_once(const std::string& path) {
    RTCDevice device = rtcNewDevice("threads=0");
    parallel_for_each_index(size_t{0}, size_t{64}, [](size_t) {});
    const auto t0 = Clock::now();
    const Scene scene = load_scene(path, {}, load_options_from_environment());
    const double load = seconds_since(t0);
    const auto t1 = Clock::now();
    { SceneAccel a(scene, scene.render.lighting); }
    const double accel = seconds_since(t1);
    bool fine = false;
    for (const Object& o : scene.objects) fine = fine || (o.placed() && o.has_fine());
    const double raw =
        raw_build(device, scene, RTC_BUILD_QUALITY_HIGH, false) + (fine ? raw_build(device, scene, RTC_BUILD_QUALITY_HIGH, true) : 0.0);
    rtcReleaseDevice(device);
    std::printf("| %s (first, fresh process) | %.3f s | %.3f s | %.3f s | %.1fx |\n", std::filesystem::path(path).filename().c_str(), load,
                accel, raw, (load + accel) / raw);
}

}  // namespace
}  // namespace bounce

int main(int argc, char** argv) {
    // Best of N in one process measures the work, not the kernel: glibc would hand a load's
    // freed pages back and the next load fault them in again (14.5 us a 4 KiB page on this
    // VM, most of a 14 400-placement load), while Embree's builds take 2 MiB pages of their
    // own. So freed memory stays with the process, as in a shot's or the lighting tool's
    // reloads; docs/benchmarks.md also gives a fresh process's first load.
    mallopt(M_MMAP_THRESHOLD, 1 << 30);
    mallopt(M_TRIM_THRESHOLD, -1);
    int repeat = 3;
    bool once = false;
    std::vector<std::string> scenes;
    for (int i = 1; i < argc; ++i) {
        if (std::strcmp(argv[i], "--repeat") == 0 && i + 1 < argc)
            repeat = std::max(1, std::atoi(argv[++i]));
        else if (std::strcmp(argv[i], "--once") == 0)
            once = true;
        else
            scenes.emplace_back(argv[i]);
    }
    if (once && scenes.size() == 1) {
        try {
            bounce::measure_once(scenes[0]);  // (the mesh cache as BOUNCE_MESH_CACHE says)
        } catch (const std::exception& e) {
            std::fprintf(stderr, "bounce_build_rate: %s\n", e.what());
            return 2;
        }
        return 0;
    }
    if (scenes.empty()) {
        std::fprintf(stderr, "usage: bounce_build_rate SCENE... [--repeat N] | bounce_build_rate --once SCENE\n");
        return 2;
    }
    std::printf(
        "| scene | triangles (unique) | placed | load, parsed | load, mesh cache | SceneAccel | raw Embree low / medium / high | "
        "SceneAccel / raw high | load parsed + SceneAccel / raw high | load cached + SceneAccel / raw high | files read |\n");
    std::printf("|---|---|---|---|---|---|---|---|---|---|---|\n");
    try {
        for (const auto& s : scenes) bounce::measure(s, repeat);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "bounce_build_rate: %s\n", e.what());
        return 2;
    }
    return 0;
}
