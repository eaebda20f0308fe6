#include "bounce/scene/instance_reader.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <iterator>
#include <map>
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
                                      "supported: place its prototype",
                                      of));
    std::vector<std::string> names;
    for (const Object& o : scene.objects) {
        if (o.name != of) {
            names.push_back(o.name);
            continue;
        }
        if (!o.prototype)
            in.fail("of", fmt::format("\"{}\" is not a prototype: give that object \"prototype\": true (it is then only placed "
                                      "by instances)",
                                      of));
        return o;
    }
    const std::string hint = closest_match(of, names);
    in.fail("of", fmt::format("no object is named \"{}\"{}", of, hint.empty() ? "" : " (did you mean \"" + hint + "\"?)"));
}

/// What placements share of their prototype (copied: the prototype moves as objects are appended).
struct Shared {
    std::shared_ptr<const TriangleMesh> coarse, fine;  ///< before the prototype's own transform
    Transform placement;                               ///< that transform
};

/// What every placement of an instancer takes from it unless its entry says otherwise (read once).
struct InstancerDefaults {
    std::string name;
    int material = -1;
    RayVisibility visible_to;
    bool matte = false;
};

/// Placement `k` of prototype `proto`, read from its entry `e` in "transforms": the entry's
/// transform applied after the prototype's own.
Object read_placement(const JsonReader& e, const Scene& scene, const Shared& proto, const InstancerDefaults& by, size_t k) {
    Object o = make_instance(e.has("name") ? e.string("name", "") : fmt::format("{}/{}", by.name, k), proto.coarse, proto.fine,
                             read_transform_keys(e) * proto.placement);
    const int own = read_material_name(e, "material", scene);
    o.material_override = own >= 0 ? own : by.material;
    o.visible_to = by.visible_to, o.matte = by.matte;
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

namespace {

/// A box that holds every vertex of a mesh with local bounds `local` as `t.point` places it:
/// the local box's image in double, widened by far more than float rounding can move a
/// placed vertex (t.point sums three products and a translation in float).
Bounds conservative_bounds(const Bounds& local, const Transform& t) {
    Bounds out;
    for (int i = 0; i < 3; ++i) {
        double centre = t.m[4 * i + 3], extent = 0, size = std::fabs(t.m[4 * i + 3]);
        for (int j = 0; j < 3; ++j) {
            const double m = t.m[4 * i + j], lo = local.lo[j], hi = local.hi[j];
            centre += m * (lo + hi) / 2, extent += std::fabs(m) * (hi - lo) / 2;
            size += std::fabs(m) * std::max(std::fabs(lo), std::fabs(hi));
        }
        const double margin = 1e-6 * size;
        out.lo[i] = static_cast<float>(centre - extent - margin), out.hi[i] = static_cast<float>(centre + extent + margin);
    }
    return out;
}

bool holds(const Bounds& outer, const Bounds& inner) {
    for (int i = 0; i < 3; ++i)
        if (!(outer.lo[i] <= inner.lo[i] && inner.hi[i] <= outer.hi[i])) return false;
    return true;
}

/// One tessellation of every placement (coarse or fine): its local box, the vertices that are
/// extreme along its local axes, and a tree of its vertices (median splits, leaves of at most
/// kLeafSize) with each node's local box, built once per shared mesh and only when some
/// placement of it needs more than its conservative box.
struct Prototype {
    static constexpr size_t kLeafSize = 64, kPlacementsWorthATree = 16;
    struct Node {
        Bounds local;
        size_t begin, end;  ///< its vertices in `vertices`
        size_t right = 0;   ///< the second child (the first follows the node); 0 = a leaf
    };
    Bounds local;
    std::vector<Vec3> extremes;  ///< none for a mesh without vertices
    std::vector<Vec3> vertices;  ///< the mesh's, in the tree's order
    std::vector<Node> nodes;
    explicit Prototype(const TriangleMesh& m) : local(m.bounds()) {
        if (m.positions.empty()) return;
        std::array<size_t, 6> at{};
        for (size_t v = 0; v < m.positions.size(); ++v)
            for (int a = 0; a < 3; ++a) {
                if (m.positions[v][a] < m.positions[at[2 * a]][a]) at[2 * a] = v;
                if (m.positions[v][a] > m.positions[at[2 * a + 1]][a]) at[2 * a + 1] = v;
            }
        for (size_t v : at) extremes.push_back(m.positions[v]);
    }
    /// The tree for `placements` placements that need it; a few place every vertex instead
    /// (one leaf), which is cheaper than splitting.
    void build_tree(const TriangleMesh& m, size_t placements) {
        vertices = m.positions;
        if (vertices.empty()) return;
        if (placements > kPlacementsWorthATree)
            split(0, vertices.size());
        else
            nodes.push_back({local, 0, vertices.size()});
    }
    void split(size_t begin, size_t end) {
        const size_t node = nodes.size();
        Bounds b;
        for (size_t v = begin; v < end; ++v) b.extend(vertices[v]);
        nodes.push_back({b, begin, end});
        if (end - begin <= kLeafSize) return;
        const Vec3 size = b.hi - b.lo;
        const int axis = size.x >= size.y && size.x >= size.z ? 0 : size.y >= size.z ? 1 : 2;
        const auto mid = static_cast<std::ptrdiff_t>(begin + (end - begin) / 2);
        std::nth_element(vertices.begin() + static_cast<std::ptrdiff_t>(begin), vertices.begin() + mid,
                         vertices.begin() + static_cast<std::ptrdiff_t>(end),
                         [axis](const Vec3& p, const Vec3& q) { return p[axis] < q[axis]; });
        split(begin, static_cast<size_t>(mid));
        nodes[node].right = nodes.size();
        split(static_cast<size_t>(mid), end);
    }
};

/// World bounds of `proto`'s vertices placed by `t`, each exactly as t.point places it, except
/// under the tree's nodes whose conservative box lies inside `known` (they cannot widen a union
/// that holds `known`): those add their conservative box. False when a vertex lands beyond the limit.
bool placed_bounds(const Prototype& proto, const Transform& t, const Bounds& known, Bounds& b) {
    std::vector<size_t> stack{0};
    while (!stack.empty()) {
        const Prototype::Node& n = proto.nodes[stack.back()];
        stack.pop_back();
        const Bounds cb = conservative_bounds(n.local, t);
        if (within(cb.lo, kMaxCoordinate) && within(cb.hi, kMaxCoordinate) && holds(known, cb)) {
            b.extend(cb.lo), b.extend(cb.hi);
        } else if (n.right) {
            stack.push_back(n.right), stack.push_back(static_cast<size_t>(&n - proto.nodes.data()) + 1);
        } else {
            for (size_t v = n.begin; v < n.end; ++v) {
                const Vec3 q = t.point(proto.vertices[v]);
                if (!within(q, kMaxCoordinate)) return false;
                b.extend(q);
            }
        }
    }
    return true;
}

/// Sets `bounds(o)` for every placement so that their union is exactly the union of their
/// exactly placed vertices, placing only the vertices (under the tree nodes, of the placements)
/// that can reach that union's surface: the other conservative boxes lie inside a box the union
/// is known to hold (the placements' prototype extremes, placed, and `given`: still objects read
/// before), so the union is bit for bit what placing every vertex gives. `beyond[k]`: placement
/// k leaves the limit.
void bound_tessellation(std::span<Object> placed, const std::function<const TriangleMesh*(const Object&)>& mesh,
                        const std::function<Bounds&(Object&)>& bounds, const Bounds& given, std::vector<uint8_t>& beyond) {
    std::map<const TriangleMesh*, Prototype> prototypes;
    for (const Object& o : placed)
        if (const TriangleMesh* m = mesh(o)) prototypes.try_emplace(m, *m);
    std::vector<Bounds> inner(placed.size());
    parallel_for_each_index(size_t{0}, placed.size(), [&](size_t k) {
        const Object& o = placed[k];
        if (const TriangleMesh* m = mesh(o))
            for (const Vec3& p : prototypes.at(m).extremes) inner[k].extend(o.placement.point(p));
    });
    Bounds known = given;
    for (const Bounds& b : inner) known.extend(b);
    std::vector<uint8_t> exact(placed.size(), 0);
    parallel_for_each_index(size_t{0}, placed.size(), [&](size_t k) {
        Object& o = placed[k];
        const TriangleMesh* m = mesh(o);
        if (!m) return;
        Bounds& b = bounds(o);
        b = conservative_bounds(prototypes.at(m).local, o.placement);
        exact[k] = !(within(b.lo, kMaxCoordinate) && within(b.hi, kMaxCoordinate) && holds(known, b));
    });
    std::map<const TriangleMesh*, size_t> trees;  // placements that need each prototype's tree
    for (size_t k = 0; k < placed.size(); ++k)
        if (exact[k]) ++trees[mesh(placed[k])];
    for (const auto& [m, n] : trees) prototypes.at(m).build_tree(*m, n);
    parallel_for_each_index(size_t{0}, placed.size(), [&](size_t k) {
        if (!exact[k]) return;
        Object& o = placed[k];
        Bounds& b = bounds(o);
        b = Bounds{};
        beyond[k] |= !placed_bounds(prototypes.at(mesh(o)), o.placement, known, b);
    });
}

}  // namespace

KnownBounds still_bounds(std::span<const Object> objects) {
    KnownBounds known;
    for (const Object& o : objects) {
        if (!o.placed() || o.moves) continue;
        known.coarse.extend(o.coarse_bounds());
        if (o.has_fine()) known.visible.extend(o.visible_mesh_bounds());
    }
    known.visible.extend(known.coarse);
    return known;
}

void bound_instances(std::span<Object> placed, const std::function<const JsonReader(size_t)>& at, const KnownBounds& known) {
    std::vector<uint8_t> beyond(placed.size(), 0);
    bound_tessellation(
        placed, [](const Object& o) { return o.local_coarse.get(); }, [](Object& o) -> Bounds& { return o.instance_bounds; }, known.coarse,
        beyond);
    bound_tessellation(
        placed, [](const Object& o) { return o.local_fine.get(); }, [](Object& o) -> Bounds& { return o.instance_visible_bounds; },
        known.visible, beyond);
    for (Object& o : placed)
        if (!o.local_fine) o.instance_visible_bounds = o.instance_bounds;
    for (size_t k = 0; k < placed.size(); ++k)
        if (beyond[k])
            at(k).fail("", fmt::format("this placement moves vertices to non-finite positions or beyond +-{:g}", kMaxCoordinate));
}

void read_instances(const JsonReader& r, const json& entries, Scene& scene, size_t index, std::span<const Object> file_instances) {
    r.only({"name", "instances", "material", "visible_to", "matte"}, "an object that places instances");
    if (!r.raw("instances").is_object()) r.fail("instances", "expected {\"of\": \"prototype name\", \"transforms\": [...]}");
    const JsonReader in(r.raw("instances"), r.at("instances"), r.ctx(), {"of", "transforms"});
    if (scene.keyed.is_object() && has_keys(scene.keyed["objects"][index]))
        r.fail("instances", "instances cannot be keyed (yet): give a moving copy an object of its own");
    const Object& proto = find_prototype(in, entries, scene);
    if (!in.has("transforms") || !in.raw("transforms").is_array() || in.raw("transforms").empty())
        in.fail(in.has("transforms") ? "transforms" : "",
                "expected \"transforms\": a non-empty array of {translate, rotate, scale} or {matrix}");
    const json& list = in.raw("transforms");
    // Each placement is an Object (no triangles of its own), an Embree instance, its share of
    // the radiosity layout and of every per-object table: refused before it could exhaust memory.
    check_memory(static_cast<double>(list.size()) * kPlacementBytes, r.ctx().file, in.at("transforms"),
                 fmt::format("{} instances (about {:.1f} KB each)", list.size(), kPlacementBytes / 1024.0));
    const Shared shared{proto.local_coarse, proto.local_fine, proto.placement};
    const auto entry = [&](size_t k) {
        const std::string at = in.at("transforms") + "/" + std::to_string(k);
        if (!list[k].is_object()) r.ctx().fail(at, fmt::format("expected a transform object, got {}", json_type_name(list[k])));
        return JsonReader(list[k], at, r.ctx(), {"translate", "rotate", "scale", "matrix", "name", "material", "visible_to", "matte"});
    };
    // Read in place at the end of the objects (read_objects reserved room for every placement),
    // then the first moves to the instancer's index: one Object each, never a second copy.
    const size_t first = scene.objects.size();
    reserve_huge(scene.objects, first + list.size());
    InstancerDefaults by{r.string("name", ""), read_material_name(r, "material", scene), {}, false};
    Object flags;
    read_object_visibility(r, flags);
    by.visible_to = flags.visible_to, by.matte = flags.matte;
    for (size_t k = 0; k < list.size(); ++k) scene.objects.push_back(read_placement(entry(k), scene, shared, by, k));
    KnownBounds known = still_bounds(std::span<const Object>(scene.objects).first(first));
    const KnownBounds files = still_bounds(file_instances);
    known.coarse.extend(files.coarse), known.visible.extend(files.visible);
    bound_instances(std::span<Object>(scene.objects).subspan(first), entry, known);
    scene.objects[index] = std::move(scene.objects[first]);
    scene.objects.erase(scene.objects.begin() + static_cast<std::ptrdiff_t>(first));
}

size_t placements_of(const json& entry) {
    if (!places_instances(entry) || !entry["instances"].is_object()) return 0;
    const json& in = entry["instances"];
    return in.contains("transforms") && in["transforms"].is_array() ? in["transforms"].size() : 0;
}

}  // namespace bounce
