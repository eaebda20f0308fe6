#include "bounce/scene/subdivision_reader.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>

#include "bounce/core/error.h"
#include "bounce/core/memory.h"
#include "bounce/dice/displacement.h"
#include "bounce/scene/item_readers.h"
#include "bounce/scene/mesh_object_files.h"

namespace bounce {

namespace {

/// Most micropolygons one object may be diced into (~150 bytes each with its BVH).
constexpr double kMaxMicropolygons = 1e8;

/// Pixels per world unit at p on the image plane of `cam` (0 behind it).
float pixels_per_unit(const Camera& cam, const Vec3& p) {
    const Vec3 forward = normalize(cam.look_at - cam.position);
    const float z = dot(p - cam.position, forward);
    if (!(z > 0)) return 0;
    return static_cast<float>(cam.height) / (2 * z * std::tan(0.5f * cam.fov * kPi / 180.0f));
}

/// Length in pixels of the segment a-b projected on the image plane of `cam` (foreshortening
/// included); where it reaches behind the camera, its length at the nearer end's depth.
float projected_pixels(const Camera& cam, const Vec3& a, const Vec3& b) {
    const Vec3 forward = normalize(cam.look_at - cam.position);
    const Vec3 right = normalize(cross(forward, cam.up)), up = cross(right, forward);
    const float za = dot(a - cam.position, forward), zb = dot(b - cam.position, forward);
    const float scale = static_cast<float>(cam.height) / (2 * std::tan(0.5f * cam.fov * kPi / 180.0f));
    if (!(za > 0 && zb > 0)) return length(b - a) * std::max(pixels_per_unit(cam, a), pixels_per_unit(cam, b));
    const Vec3 da = a - cam.position, db = b - cam.position;
    const float dx = dot(da, right) / za - dot(db, right) / zb, dy = dot(da, up) / za - dot(db, up) / zb;
    return std::sqrt(dx * dx + dy * dy) * scale;
}

/// The object's "displacement" block into `surf` (which has its control mesh).
void read_displacement(const JsonReader& r, SubdivSurface& surf) {
    JsonReader d(r.raw("displacement"), r.at("displacement"), r.ctx(), {"map", "scale", "midpoint"});
    if (!d.has("map")) d.fail("", "a displacement needs a \"map\"");
    const std::string map = d.file("map", true);
    surf.displacement.scale = d.number("scale", 0, -kMaxCoordinate, kMaxCoordinate, true);
    surf.displacement.midpoint = d.number("midpoint", 0.5f, -1e3, 1e3);
    try {
        surf.displacement.map = std::make_shared<DisplacementMap>(map);
    } catch (const InputError& e) {
        d.fail("map", e.what());
    }
    if (surf.control.face_uvs.empty()) d.fail("map", "the control mesh has no uvs to look the map up with");
}

}  // namespace

void read_subdivision_object(const JsonReader& r, Scene& scene, int mat, Object& obj, SubdivScheme scheme, const DicingSettings& dicing) {
    SubdivSurface surf;
    surf.scheme = scheme;
    surf.boundary = r.choice("boundary", "edge-and-corner", {"edge-only", "edge-and-corner"}) == "edge-only"
                        ? SubdivBoundary::EdgeOnly
                        : SubdivBoundary::EdgeAndCorner;
    if (r.has("fine_subdivisions"))
        r.fail("fine_subdivisions",
               "a subdivision surface is diced from the camera by render.shading_rate (rays see render.ray_level), not fine_subdivisions");
    const std::string file = r.file("file", true);
    MeshInputs read = mesh_inputs(r, "file");
    try {
        obj.placement = read_transform(r);
        parsing_mesh(scene, [&] { surf.control = load_control_mesh(file, obj.name, scene.materials, mat, obj.placement, &read); });
        check_control_mesh(surf.control, surf.scheme);
        if (surf.control.dropped_vertex_colors) note_ignored(scene, file, "COLOR_0 (vertex colours) on a subdivision surface");
    } catch (const InputError& e) {
        r.fail("file", e.what());
    }
    record_inputs(r, "file", read);
    note_unread(scene, file, mat, obj.name);
    if (r.has("displacement")) read_displacement(r, surf);
    const int ray_level = std::min(dicing.ray_level, dicing.max_level);
    const int level = dicing_level(
        surf.control, [&](const Vec3& p) { return pixels_per_unit(scene.camera, p); }, dicing.shading_rate, ray_level, dicing.max_level);
    // The fine tessellation per control edge: about shading_rate pixels per diced edge from the
    // camera, never coarser than the ray tessellation (docs/displacement.md).
    const auto rate = [&](const Vec3& a, const Vec3& b) {
        const float px = projected_pixels(scene.camera, a, b) / dicing.shading_rate;
        return static_cast<int>(std::clamp(std::round(px), static_cast<float>(1 << ray_level), static_cast<float>(1 << dicing.max_level)));
    };
    // Refuse a dicing that cannot fit before allocating it: per face its largest edge rate
    // squared (twice for quads, half per corner for n-gons), and the ray tessellation.
    double micropolygons = 0;
    int largest = 1 << ray_level;
    for (size_t f = 0, k = 0; f < surf.control.face_count(); k += static_cast<size_t>(surf.control.face_sizes[f++])) {
        const int n = surf.control.face_sizes[f];
        int rmax = 1;
        for (int i = 0; i < n; ++i)
            rmax = std::max(
                rmax, rate(surf.control.positions[static_cast<size_t>(surf.control.face_vertices[k + static_cast<size_t>(i)])],
                           surf.control.positions[static_cast<size_t>(surf.control.face_vertices[k + static_cast<size_t>((i + 1) % n)])]));
        largest = std::max(largest, rmax);
        const double cells = static_cast<double>(rmax) * rmax, coarse = std::pow(4.0, ray_level);
        micropolygons += (n == 3 ? 1.0 : n == 4 ? 2.0 : n / 2.0) * (cells + coarse);
    }
    if (micropolygons > kMaxMicropolygons)
        r.fail("", fmt::format("dicing {} gives {:.3g} micropolygons (about {:.0f} GiB); the limit is {:.0e}: raise "
                               "render.shading_rate or lower render.max_level / render.ray_level",
                               obj.name, micropolygons, micropolygons * 150 / (1 << 30), kMaxMicropolygons));
    if (std::string why =
            memory_shortfall(micropolygons * 150, fmt::format("dicing {} into {:.3g} micropolygons", obj.name, micropolygons));
        !why.empty())
        r.fail("", why + ": raise render.shading_rate or lower render.max_level / render.ray_level");
    const auto t0 = std::chrono::steady_clock::now();
    try {
        obj.coarse = dice(surf, ray_level);
        if (largest > 1 << ray_level) obj.fine = dice_adaptive(surf, rate);
    } catch (const InputError& e) {  // a map that cannot be read after all, or OpenSubdiv refusing the mesh
        const bool map = surf.displacement.map && e.file() == surf.displacement.map->path();
        r.fail(map ? "displacement/map" : "file", e.what());
    }
    obj.dicing_level = level;
    if (surf.displacement.active())
        obj.displacement_bound =
            std::abs(surf.displacement.scale) * std::max(std::abs(surf.displacement.midpoint), std::abs(1 - surf.displacement.midpoint));
    obj.dicing_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    obj.surface = std::make_shared<const SubdivSurface>(std::move(surf));
}

}  // namespace bounce
