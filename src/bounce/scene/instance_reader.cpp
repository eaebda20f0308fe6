#include "bounce/scene/instance_reader.h"

#include <fmt/format.h>

#include <iterator>
#include <memory>
#include <utility>

#include "bounce/core/error.h"
#include "bounce/core/memory.h"
#include "bounce/core/parallel.h"
#include "bounce/scene/item_readers.h"
#include "bounce/scene/keyframes.h"
#include "bounce/scene/link_reader.h"
#include "bounce/scene/object_reader.h"

namespace bounce {

using nlohmann::json;

bool places_instances(const json& entry) { return entry.is_object() && entry.contains("instances"); }

namespace {

/// The prototype named by the instancer's "of" (`entries`: the scene file's objects).
const Object& find_prototype(const JsonReader& in, const json& entries, const Scene& scene) {
    const std::string of = in.string("of", "", true);
    for (const json& e : entries)
        if (places_instances(e) && e.value("name", json()) == of)
            in.fail("of", fmt::format("\"{}\" is not a prototype but places instances itself; instances of instances are not "
                                      "supported: place its prototype", of));
    std::vector<std::string> names;
    for (const Object& o : scene.objects) {
        if (o.name != of) {
            names.push_back(o.name);
            continue;
        }
        if (!o.prototype)
            in.fail("of", fmt::format("\"{}\" is not a prototype: give that object \"prototype\": true (it is then only placed "
                                      "by instances)", of));
        return o;
    }
    const std::string hint = closest_match(of, names);
    in.fail("of", fmt::format("no object is named \"{}\"{}", of, hint.empty() ? "" : " (did you mean \"" + hint + "\"?)"));
}

/// World bounds of `mesh` placed by `t`; false when a vertex lands beyond the coordinate limit.
bool placed_bounds(const TriangleMesh& mesh, const Transform& t, Bounds& b) {
    for (const Vec3& p : mesh.positions) {
        const Vec3 q = t.point(p);
        if (!within(q, kMaxCoordinate)) return false;
        b.extend(q);
    }
    return true;
}

/// What placements share of their prototype (copied: the prototype moves as objects are appended).
struct Shared {
    std::shared_ptr<const TriangleMesh> coarse, fine;  ///< before the prototype's own transform
    Transform placement;                               ///< that transform
};

/// Placement `k` of prototype `proto`, read from its entry `e` in "transforms": the entry's
/// transform applied after the prototype's own.
Object read_placement(const JsonReader& r, const JsonReader& e, const Scene& scene, const Shared& proto, size_t k) {
    Object o = make_instance(e.string("name", fmt::format("{}/{}", r.string("name", ""), k)), proto.coarse, proto.fine,
                             read_transform_keys(e) * proto.placement);
    const int own = read_material_name(e, "material", scene);
    o.material_override = own >= 0 ? own : read_material_name(r, "material", scene);
    read_object_visibility(r, o);
    read_object_visibility(e, o);  // the placement's own flags over the instancer's
    return o;
}

}  // namespace

Object make_instance(std::string name, std::shared_ptr<const TriangleMesh> coarse, std::shared_ptr<const TriangleMesh> fine,
                     const Transform& placement) {
    Object o;
    o.instance = true;
    o.name = std::move(name);
    o.placement = placement;
    o.local_coarse = std::move(coarse), o.local_fine = std::move(fine);
    return o;
}

void bound_instances(std::span<Object> placed, const std::function<const JsonReader(size_t)>& at) {
    std::vector<uint8_t> beyond(placed.size(), 0);
    parallel_for_each_index(size_t{0}, placed.size(), [&](size_t k) {
        Object& o = placed[k];
        o.instance_bounds = o.instance_visible_bounds = Bounds{};
        bool ok = placed_bounds(*o.local_coarse, o.placement, o.instance_bounds);
        if (!o.local_fine) o.instance_visible_bounds = o.instance_bounds;
        else ok = ok && placed_bounds(*o.local_fine, o.placement, o.instance_visible_bounds);
        beyond[k] = !ok;
    });
    for (size_t k = 0; k < placed.size(); ++k)
        if (beyond[k]) at(k).fail("", fmt::format("this placement moves vertices to non-finite positions or beyond +-{:g}", kMaxCoordinate));
}

void read_instances(const JsonReader& r, const json& entries, Scene& scene, size_t index) {
    r.only({"name", "instances", "material", "visible_to", "matte"}, "an object that places instances");
    if (!r.raw("instances").is_object()) r.fail("instances", "expected {\"of\": \"prototype name\", \"transforms\": [...]}");
    const JsonReader in(r.raw("instances"), r.at("instances"), r.ctx(), {"of", "transforms"});
    if (scene.keyed.is_object() && has_keys(scene.keyed["objects"][index]))
        r.fail("instances", "instances cannot be keyed (yet): give a moving copy an object of its own");
    const Object& proto = find_prototype(in, entries, scene);
    if (!in.has("transforms") || !in.raw("transforms").is_array() || in.raw("transforms").empty())
        in.fail(in.has("transforms") ? "transforms" : "", "expected \"transforms\": a non-empty array of {translate, rotate, scale} or {matrix}");
    const json& list = in.raw("transforms");
    // Each placement is an Object (no triangles of its own): refused before it could exhaust memory.
    check_memory(static_cast<double>(list.size()) * (sizeof(Object) + 64), r.ctx().file, in.at("transforms"),
                 fmt::format("{} instances", list.size()));
    const Shared shared{proto.local_coarse, proto.local_fine, proto.placement};
    const auto entry = [&](size_t k) {
        const std::string at = in.at("transforms") + "/" + std::to_string(k);
        if (!list[k].is_object()) r.ctx().fail(at, fmt::format("expected a transform object, got {}", json_type_name(list[k])));
        return JsonReader(list[k], at, r.ctx(), {"translate", "rotate", "scale", "matrix", "name", "material", "visible_to", "matte"});
    };
    std::vector<Object> placed;
    placed.reserve(list.size());
    for (size_t k = 0; k < list.size(); ++k) placed.push_back(read_placement(r, entry(k), scene, shared, k));
    bound_instances(placed, entry);
    scene.objects[index] = std::move(placed[0]);
    std::move(placed.begin() + 1, placed.end(), std::back_inserter(scene.objects));
}

}  // namespace bounce
