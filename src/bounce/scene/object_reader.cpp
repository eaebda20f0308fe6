#include "bounce/scene/object_reader.h"

#include <fmt/format.h>

#include <cmath>

#include "bounce/core/error.h"
#include "bounce/core/memory.h"
#include "bounce/dice/subdivision.h"
#include "bounce/scene/fur_reader.h"
#include "bounce/scene/instance_reader.h"
#include "bounce/scene/item_readers.h"
#include "bounce/scene/keyframes.h"
#include "bounce/scene/link_reader.h"
#include "bounce/scene/mesh_animation.h"
#include "bounce/scene/mesh_import.h"
#include "bounce/scene/mesh_object_files.h"
#include "bounce/scene/subdivision_reader.h"

namespace bounce {

using nlohmann::json;

const std::vector<std::string>& object_keys() {
    static const std::vector<std::string> keys = {"name",         "type",   "file",      "material",     "transform",   "fine_subdivisions",
                                                  "vertices",     "center", "radius",    "subdivisions", "subdivision", "boundary",
                                                  "displacement", "fur",    "animation", "visible_to",   "matte",       "prototype",
                                                  "instances"};
    return keys;
}

int material_index(const Scene& scene, const std::string& name) {
    for (size_t i = 0; i < scene.materials.size(); ++i)
        if (scene.materials[i].name == name) return static_cast<int>(i);
    return -1;
}

int read_material_name(const JsonReader& r, const std::string& key, const Scene& scene) {
    if (!r.has(key)) return -1;
    const std::string name = r.string(key, "");
    const int mat = material_index(scene, name);
    if (mat >= 0) return mat;
    std::vector<std::string> names;
    for (const auto& m : scene.materials) names.push_back(m.name);
    const std::string hint = closest_match(name, names);
    r.fail(key, fmt::format("unknown material \"{}\"{}", name, hint.empty() ? "" : " (did you mean \"" + hint + "\"?)"));
}

namespace {

/// The keys each object type reads.
const std::vector<std::string>& keys_of_type(const std::string& type, bool subdivision) {
    static const std::vector<std::string> mesh = {"name",        "type", "file",     "material", "transform", "fine_subdivisions",
                                                  "subdivision", "fur",  "animation"};
    static const std::vector<std::string> subdiv = {"name",        "type",     "file",         "material", "transform",
                                                    "subdivision", "boundary", "displacement", "fur"};
    static const std::vector<std::string> quad = {"name", "type", "vertices", "material", "transform", "fine_subdivisions", "fur"};
    static const std::vector<std::string> sphere = {"name",     "type",      "center", "radius", "subdivisions", "fine_subdivisions",
                                                    "material", "transform", "fur"};
    // Every type also takes the lighter's controls (link_reader.h).
    static const auto with_controls = [](std::vector<std::string> keys) {
        keys.insert(keys.end(), {"visible_to", "matte", "prototype"});
        return keys;
    };
    static const std::vector<std::string> mesh_c = with_controls(mesh), subdiv_c = with_controls(subdiv), quad_c = with_controls(quad),
                                          sphere_c = with_controls(sphere);
    if (type == "mesh") return subdivision ? subdiv_c : mesh_c;
    return type == "quad" ? quad_c : sphere_c;
}

}  // namespace

namespace {
/// The pose of a mesh object's file at `frame`: its "animation" clip, played from the shot's first frame.
MeshPose mesh_pose(const JsonReader& r, const Scene& scene, double frame) {
    MeshPose pose;
    if (!r.has("animation")) return pose;
    const nlohmann::json& a = r.raw("animation");
    if (a.is_number_unsigned())
        pose.clip = std::to_string(a.get<uint64_t>());
    else if (a.is_string() && !a.get<std::string>().empty())
        pose.clip = a.get<std::string>();
    else
        r.fail("animation", "expected the name or the number of one of the file's animations");
    pose.seconds = (frame - scene.shot.first) / scene.shot.fps;
    return pose;
}
}  // namespace

TriangleMesh posed_visible_mesh(const JsonReader& r, const Scene& scene, double frame) {
    std::vector<Material> materials = scene.materials;  // the file's own are added to a copy
    TriangleMesh mesh;
    try {
        MeshInputs read = mesh_inputs(r, "file");  // (its inputs were recorded when the object was read)
        mesh = load_mesh_file(r.file("file", true), "", materials, -1, &read, mesh_pose(r, scene, frame));
    } catch (const NoSuchClip& e) {
        r.fail("animation", e.what());
    } catch (const InputError& e) {
        r.fail("file", e.what());
    }
    mesh.transform(read_transform(r));
    const int fine = r.integer("fine_subdivisions", 0, 0, 6);
    return fine > 0 ? subdivide_linear(mesh, fine) : mesh;
}

namespace {
/// Whether object `index`'s transform is keyed in the scene file (before keys were taken at the frame).
bool placement_keyed(const Scene& scene, size_t index) {
    if (!scene.keyed.is_object() || !scene.keyed.contains("objects") || !scene.keyed["objects"].is_array()) return false;
    const nlohmann::json& objects = scene.keyed["objects"];
    if (index >= objects.size() || !objects[index].is_object() || !objects[index].contains("transform")) return false;
    return has_keys(objects[index]["transform"]);
}

/// A rigid mover keeps its tessellations as they are before its placement: ray tracing places
/// them with it (accel/bvh.h), so a shot's frames move it without building its BVH again. So
/// does a prototype: its instances place them with their placement times its own.
bool keeps_local(const Object& obj) { return (obj.moves && !obj.deforms) || obj.prototype; }
void keep_local(Object& obj, const TriangleMesh& coarse, const TriangleMesh* fine) {
    if (!keeps_local(obj)) return;
    obj.local_coarse = std::make_shared<const TriangleMesh>(coarse);
    if (fine) obj.local_fine = std::make_shared<const TriangleMesh>(*fine);
}
}  // namespace

namespace {
/// The visible surface of mover `obj` (object `index`, read from `r` at the frame) as it stands
/// at the shot's first frame: the groom, which every frame's pose carries (fur.h, carry_fur).
TriangleMesh groom_surface(const JsonReader& r, const Scene& scene, size_t index, const Object& obj) {
    if (scene.frame == scene.shot.first) return obj.visible();
    const json first = scene.keyed.is_object() ? evaluate_keys(scene.keyed, scene.shot.first, r.ctx()) : json();
    const bool keyed = first.is_object() && first.contains("objects") && first["objects"].is_array() && index < first["objects"].size();
    const JsonReader then = keyed ? JsonReader(first["objects"][index], fmt::format("/objects/{}", index), r.ctx(), object_keys()) : r;
    if (obj.deforms) {
        TriangleMesh posed = posed_visible_mesh(then, scene, scene.shot.first);
        return same_triangles(posed, obj.visible()) ? posed : obj.visible();
    }
    const Transform placed = read_transform(then);
    TriangleMesh groom = obj.visible();
    if (placed != obj.placement) groom.transform(placed * obj.placement.inverse());
    return groom;
}

/// An object's fur: grown on its surface, or for a mover grown on its groom and carried to the
/// frame's pose, so that a shot's frames show the same strands moving with the surface.
void read_object_fur(const JsonReader& fur, const JsonReader& r, const Scene& scene, const DicingSettings& dicing, size_t index,
                     Object& obj) {
    if (!obj.moves) {
        obj.fur = read_fur(fur, obj.visible(), dicing);
        return;
    }
    const TriangleMesh groom = groom_surface(r, scene, index, obj);
    std::shared_ptr<Fur> grown = read_fur(fur, groom, dicing);
    carry_fur(*grown, groom, obj.visible());
    obj.fur = std::move(grown);
}
}  // namespace

namespace {
/// Instances of the meshes a mesh file's nodes share, named "<object>/<node>", placed by the
/// node's world transform then the object's; `fine` levels of linear subdivision for the camera.
/// Each takes the object's lighter's controls (visibility, matte).
std::vector<Object> place_shared_meshes(const JsonReader& r, const Object& obj, std::vector<MeshFileParts::Shared>& shared, int fine,
                                        const KnownBounds& known) {
    std::vector<Object> placed;
    double uses = 0;  // each an Object of its own: refused before they could exhaust memory
    for (const MeshFileParts::Shared& s : shared) uses += static_cast<double>(s.uses.size());
    check_memory(uses * kPlacementBytes, r.ctx().file, r.at("file"), fmt::format("{:.0f} instances of the file's shared meshes", uses));
    reserve_huge(placed, static_cast<size_t>(uses));
    for (MeshFileParts::Shared& s : shared) {
        auto local_fine = fine > 0 ? std::make_shared<const TriangleMesh>(subdivide_linear(s.mesh, fine)) : nullptr;
        const auto local = std::make_shared<const TriangleMesh>(std::move(s.mesh));
        for (size_t k = 0; k < s.uses.size(); ++k) {
            const std::string node = s.uses[k].node.empty() ? fmt::format("node{}", placed.size()) : s.uses[k].node;
            placed.push_back(make_instance(fmt::format("{}/{}", obj.name, node), local, local_fine, obj.placement * s.uses[k].world));
            placed.back().visible_to = obj.visible_to, placed.back().matte = obj.matte;
        }
    }
    bound_instances(
        placed, [&](size_t) { return r; }, known);
    return placed;
}

/// Object `obj` (read from `r`) kept only to be placed by instances: its tessellations become
/// the shared ones every instance traces. What instances cannot share is refused here.
void make_prototype(const JsonReader& r, const Scene& scene, Object& obj) {
    const auto refuse = [&](const std::string& key, const std::string& why) {
        r.fail(key, fmt::format("a prototype (\"prototype\": true) {}: instances share one tessellation, still, "
                                "placed as it is (docs/scene-format.md, \"Instances\")",
                                why));
    };
    if (obj.surface) refuse("subdivision", "cannot be a subdivision surface (it is diced for where it stands)");
    if (obj.fur) refuse("fur", "cannot grow fur");
    if (obj.deforms) refuse("animation", "cannot play an animation");
    if (obj.moves) refuse("transform", "cannot have a keyed transform");
    for (uint32_t m : obj.coarse.face_materials)
        if (scene.materials[m].is_emissive()) refuse("", fmt::format("cannot emit light (material \"{}\")", scene.materials[m].name));
    // Its tessellations before its placement were kept (keep_local): the world ones go.
    obj.coarse = {}, obj.fine = {};
}
}  // namespace

void check_generated_geometry(const JsonReader& root, const nlohmann::json& objects, const DicingSettings& dicing) {
    // An icosphere of level L has 20 x 4^L triangles; with its vertices, normals and its share of
    // a BVH, about 100 bytes each.
    constexpr double kBytesPerTriangle = 100;
    double triangles = 0;
    size_t spheres = 0;
    for (const nlohmann::json& o : objects) {
        // (A type that is not a string is read_object's to name: value() would throw here.)
        if (!o.is_object() || !o.contains("type") || o["type"] != "sphere") continue;
        const auto level = [&](const char* key, int def) {
            const nlohmann::json& v = o.value(key, nlohmann::json(def));
            return v.is_number_integer() ? std::clamp(v.get<int>(), 0, 8) : def;  // read_object names a bad one
        };
        const int coarse = level("subdivisions", 3), fine = level("fine_subdivisions", 2);
        triangles += 20 * std::pow(4.0, coarse) + (fine > 0 ? 20 * std::pow(4.0, std::min(8, coarse + fine)) : 0);
        ++spheres;
    }
    const double bytes = triangles * kBytesPerTriangle, budget = static_cast<double>(dicing.memory_budget) * 1073741824.0;
    if (bytes > budget)
        root.fail("objects", fmt::format("{} spheres would be tessellated into {:.3g} triangles, about {:.1f} GiB, over "
                                         "render.memory_budget ({:g} GiB); lower their subdivisions or fine_subdivisions",
                                         spheres, triangles, bytes / 1073741824.0, dicing.memory_budget));
    if (std::string why = memory_shortfall(bytes, fmt::format("tessellating {} spheres", spheres)); !why.empty()) root.fail("objects", why);
}

namespace {

/// The object's material, else the scene's "default" (made when there is none).
uint32_t default_material(Scene& scene, int mat) {
    if (mat >= 0) return static_cast<uint32_t>(mat);
    int d = material_index(scene, "default");
    if (d < 0) {
        Material m;
        m.name = "default";
        scene.materials.push_back(m);
        d = static_cast<int>(scene.materials.size() - 1);
    }
    return static_cast<uint32_t>(d);
}

/// Places a mesh or quad by its transform, keeping its local copy, and splits it `fine` times
/// (linearly) for primary visibility.
void place_with_fine(Object& obj, int fine) {
    if (fine > 0 && keeps_local(obj)) {
        const TriangleMesh local_fine = subdivide_linear(obj.coarse, fine);
        keep_local(obj, obj.coarse, &local_fine);
    } else {
        keep_local(obj, obj.coarse, nullptr);
    }
    obj.coarse.transform(obj.placement);
    if (fine > 0) obj.fine = subdivide_linear(obj.coarse, fine);
}

/// A mesh file without subdivision: its triangles (the meshes several of its nodes place go to
/// `shared`), posed by its animation. Returns its fine_subdivisions.
int read_mesh_object(const JsonReader& r, Scene& scene, int mat, Object& obj, std::vector<MeshFileParts::Shared>& shared) {
    std::string file = r.file("file", true);
    const int fine = r.integer("fine_subdivisions", 0, 0, 6);
    MeshInputs read = mesh_inputs(r, "file");
    // An animation of the file plays over the shot: from its start at the shot's first frame.
    const MeshPose pose = mesh_pose(r, scene, scene.frame);
    obj.deforms = !pose.clip.empty();
    obj.moves = obj.moves || obj.deforms;
    // Meshes its nodes share become instances, unless it moves, grows fur or is a prototype
    // (instances of instances): then every node's copy is flattened into its mesh, as before.
    const bool may_share = !obj.moves && !obj.prototype && !r.has("fur");
    try {
        parsing_mesh(scene, [&] {
            if (may_share) {
                MeshFileParts parts = load_mesh_parts(file, obj.name, scene.materials, mat, &read);
                obj.coarse = std::move(parts.once);
                shared = std::move(parts.shared);
            } else {
                obj.coarse = load_mesh_file(file, obj.name, scene.materials, mat, &read, pose);
            }
        });
    } catch (const NoSuchClip& e) {
        r.fail(r.has("animation") ? "animation" : "file", e.what());
    } catch (const InputError& e) {
        r.fail("file", e.what());
    }
    record_inputs(r, "file", read);
    note_unread(scene, file, mat, obj.name);
    obj.placement = read_transform(r);
    place_with_fine(obj, fine);
    return fine;
}

/// A quad of four vertices. Returns its fine_subdivisions.
int read_quad_object(const JsonReader& r, Scene& scene, int mat, Object& obj) {
    const json& v = r.has("vertices") ? r.raw("vertices") : json();
    if (!v.is_array() || v.size() != 4) r.fail(r.has("vertices") ? "vertices" : "", "a quad needs \"vertices\": four [x,y,z] points");
    Vec3 p[4];
    for (size_t i = 0; i < 4; ++i) p[i] = r.to_vec3(v[i], r.at("vertices") + "/" + std::to_string(i));
    if (length(cross(p[1] - p[0], p[2] - p[0])) == 0) r.fail("vertices", "quad is degenerate (zero area)");
    const int fine = r.integer("fine_subdivisions", 0, 0, 8);
    obj.coarse = make_quad(p[0], p[1], p[2], p[3], default_material(scene, mat));
    obj.placement = read_transform(r);
    place_with_fine(obj, fine);
    return fine;
}

/// An icosphere, finer for primary visibility. Returns its extra fine levels.
int read_sphere_object(const JsonReader& r, Scene& scene, int mat, Object& obj) {
    Vec3 c = r.vec3("center", {});
    auto radius = static_cast<float>(r.number("radius", 1, 0, kMaxCoordinate));
    if (radius <= 0) r.fail("radius", "radius must be > 0");
    int level = r.integer("subdivisions", 3, 0, 8);
    const int fine = r.integer("fine_subdivisions", 2, 0, 8 - level);
    uint32_t m = default_material(scene, mat);
    obj.coarse = make_icosphere(c, radius, level, m);
    const Transform t = obj.placement = read_transform(r);
    if (fine > 0) obj.fine = make_icosphere(c, radius, level + fine, m);
    keep_local(obj, obj.coarse, fine > 0 ? &obj.fine : nullptr);
    obj.coarse.transform(t);
    if (fine > 0) obj.fine.transform(t);
    return fine;
}

}  // namespace

void read_object(const JsonReader& r, Scene& scene, const DicingSettings& dicing, size_t index, std::vector<Object>& later) {
    Object obj;
    obj.name = r.string("name", fmt::format("object{}", index));
    obj.moves = placement_keyed(scene, index);  // or, below, it plays an animation of its file
    obj.prototype = r.boolean("prototype", false);
    std::string type = r.choice("type", r.has("file") ? "mesh" : "", {"mesh", "quad", "sphere"});
    const bool subdivided = type == "mesh" && r.has("subdivision") && r.raw("subdivision") != "none";
    r.only(keys_of_type(type, subdivided), type != "mesh" ? "a " + type
                                           : subdivided   ? "a subdivision surface"
                                                          : "a mesh without \"subdivision\"");
    const int mat = read_material_name(r, "material", scene);
    int fine = 0;
    std::vector<MeshFileParts::Shared> shared;  // a mesh file's meshes that several of its nodes place
    const std::string subdivision = r.choice("subdivision", "none", {"none", "catmull-clark", "loop"});
    if (type == "mesh" && subdivision != "none") {
        read_subdivision_object(r, scene, mat, obj, subdivision == "loop" ? SubdivScheme::Loop : SubdivScheme::CatmullClark, dicing);
    } else if (type == "mesh") {
        fine = read_mesh_object(r, scene, mat, obj, shared);
    } else if (type == "quad") {
        fine = read_quad_object(r, scene, mat, obj);
    } else {
        fine = read_sphere_object(r, scene, mat, obj);
    }
    read_object_visibility(r, obj);  // (before its shared meshes are placed: they take its controls)
    KnownBounds known;               // (only a file with shared meshes needs it)
    if (!shared.empty()) {
        known = still_bounds(scene.objects);
        const KnownBounds earlier = still_bounds(later);
        known.coarse.extend(earlier.coarse), known.visible.extend(earlier.visible);
    }
    std::vector<Object> placed = place_shared_meshes(r, obj, shared, fine, known);
    if (obj.coarse.triangle_count() == 0 && !placed.empty()) {  // the file's meshes are all shared
        obj = std::move(placed.front());
        placed.erase(placed.begin());
    }
    if (later.empty())
        later = std::move(placed);  // (the Objects stay where they are)
    else
        later.insert(later.end(), std::make_move_iterator(placed.begin()), std::make_move_iterator(placed.end()));
    if (obj.coarse.triangle_count() == 0 && !obj.instance) r.fail(type == "mesh" ? "file" : "", "mesh has no triangles");
    for (const auto& p : obj.coarse.positions)
        if (!within(p, kMaxCoordinate))
            r.fail("", fmt::format("mesh has vertex positions that are not finite or beyond +-{:g} (after the transform)", kMaxCoordinate));
    if (r.has("fur")) read_object_fur(JsonReader(r.raw("fur"), r.at("fur"), r.ctx(), fur_keys()), r, scene, dicing, index, obj);
    if (obj.prototype) make_prototype(r, scene, obj);
    scene.objects.push_back(std::move(obj));
}
}  // namespace bounce
