// Instances: one prototype placed many times ("instances": {"of": "chair", "transforms": [...]}).
// Every placement is an Object of its own (its name, material override, visibility and light
// links are an object's), sharing the prototype's tessellations: memory grows with prototypes,
// not placements, and ray tracing places one BVH per prototype (accel/parts.h).
#pragma once

#include <cstddef>
#include <functional>
#include <memory>
#include <span>
#include <string>

#include "bounce/scene/json_reader.h"
#include "bounce/scene/scene.h"

namespace bounce {

/// What a render holds per placement, measured (10^5 and 2 x 10^5 placements of a sphere:
/// 2.6 KB each without bounce light, 3.3 KB with the cache's radiosity): the estimate a scene's
/// placements are refused by before they are read.
inline constexpr double kPlacementBytes = 3400;

/// Whether a scene file's object entry places instances.
bool places_instances(const nlohmann::json& entry);

/// A placement of the shared tessellations `coarse` and `fine` (null: none) by `placement`,
/// named `name`; its world bounds are bound_instances' work.
Object make_instance(std::string name, std::shared_ptr<const TriangleMesh> coarse, std::shared_ptr<const TriangleMesh> fine,
                     const Transform& placement);
/// Sets every placement's world bounds, in parallel, so that their union is exactly the box of
/// every placed vertex (Scene::bounds is the same bit for bit as the flat geometry's). Only the
/// placements that can reach that union's surface place all their prototype's vertices; the
/// others keep a conservative box inside it (placing every vertex was most of a big instanced
/// scene's load). Fails at `at(k)` for the first placement `k` that moves a vertex beyond the
/// coordinate limit, as a serial loop would.
/// `known`: boxes the scene's bounds hold whatever comes later (still_bounds of the objects read
/// before): a placement inside them needs no vertex placed.
struct KnownBounds {
    Bounds coarse, visible;
};
void bound_instances(std::span<Object> placed, const std::function<const JsonReader(size_t)>& at, const KnownBounds& known = {});

/// The boxes of `objects` that are placed and still, as Scene::bounds and Scene::visible_bounds
/// take them (movers left out: Scene::size holds only the still ones).
KnownBounds still_bounds(std::span<const Object> objects);

/// Reads instancer number `index` (read from `r`): its first placement takes `scene.objects[index]`
/// (held empty for it while the other objects were read, so every entry keeps its index), the
/// others are appended. Its prototype must be read already; `entries` are the scene file's objects.
/// `file_instances`: the placements of mesh files' shared meshes read so far (appended last).
void read_instances(const JsonReader& r, const nlohmann::json& entries, Scene& scene, size_t index, std::span<const Object> file_instances);

/// How many placements a scene file's object entry asks for (0 unless it places instances):
/// what read_objects reserves room for before any is read.
size_t placements_of(const nlohmann::json& entry);

}  // namespace bounce
