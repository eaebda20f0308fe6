#include "bounce/scene/changes.h"
#include "bounce/scene/opacity.h"

#include <map>
#include <optional>
#include <utility>

namespace bounce {

bool SceneChanges::moving() const {
    for (const ObjectMotion& m : objects)
        if (m.kind != ObjectMotion::Kind::Static) return true;
    return false;
}

namespace {

bool same_fur(const Object& a, const Object& b) {
    if (!a.fur || !b.fur) return !a.fur && !b.fur;
    return a.fur->vertices == b.fur->vertices;
}

/// Object bounds including its fine tessellation and fur.
Bounds object_bounds(const Object& o) {
    Bounds b = o.coarse_bounds();
    if (o.has_fine()) b.extend(o.visible_mesh_bounds());
    if (o.fur)
        for (size_t i = 0; i + 2 < o.fur->vertices.size(); i += 4)
            b.extend(Vec3{o.fur->vertices[i], o.fur->vertices[i + 1], o.fur->vertices[i + 2]});
    return b;
}

/// Two frames' meshes compared once per pair: a prototype's thousands of placements share one
/// pair of tessellations, which would otherwise be compared once per placement.
class MeshComparisons {
  public:
    bool same_positions(const TriangleMesh& a, const TriangleMesh& b) {
        std::optional<bool>& same = known_[{&a, &b}].positions;
        if (!same) same = a.positions == b.positions;
        return *same;
    }
    bool same_indices(const TriangleMesh& a, const TriangleMesh& b) {
        std::optional<bool>& same = known_[{&a, &b}].indices;
        if (!same) same = a.indices == b.indices;
        return *same;
    }
    bool same_topology(const TriangleMesh& a, const TriangleMesh& b) {
        return same_indices(a, b) && a.positions.size() == b.positions.size();
    }
    /// Two frames' instances place the same shape.
    bool same_shape(const Object& before, const Object& now) {
        return before.instance && now.instance && same_positions(*before.local_coarse, *now.local_coarse) &&
               (before.local_fine == nullptr) == (now.local_fine == nullptr) &&
               (!now.local_fine || same_positions(*before.local_fine, *now.local_fine));
    }

  private:
    struct Same {
        std::optional<bool> positions, indices;  ///< (each compared when first asked)
    };
    std::map<std::pair<const TriangleMesh*, const TriangleMesh*>, Same> known_;
};

/// How an instance moved: its shared shape (`same_shape`), material and placement.
ObjectMotion instance_motion(const Object& before, const Object& now, bool same_shape) {
    ObjectMotion m;
    const bool same_material = before.material_override == now.material_override;
    if (same_shape && same_material && before.placement == now.placement) return m;
    m.swept = object_bounds(before);
    m.swept.extend(object_bounds(now));
    // Another material is handled as a new surface: its radiosity is laid out and baked anew.
    m.kind = same_shape && same_material ? ObjectMotion::Kind::Rigid : ObjectMotion::Kind::Deforming;
    m.delta = now.placement * before.placement.inverse();
    return m;
}

ObjectMotion motion_of(const Object& before, const Object& now, MeshComparisons& meshes) {
    if (before.instance || now.instance) return instance_motion(before, now, meshes.same_shape(before, now));
    ObjectMotion m;
    if (meshes.same_positions(before.coarse, now.coarse) && same_fur(before, now)) return m;
    m.swept = object_bounds(before);
    m.swept.extend(object_bounds(now));
    // Rigid: the same shape under another placement (same vertices once both are undone).
    m.kind = ObjectMotion::Kind::Deforming;
    if (!now.deforms && !before.deforms && !(before.placement == now.placement)) {
        const Transform delta = now.placement * before.placement.inverse();
        bool rigid = true;
        const float tolerance = 1e-4f * std::max(1e-6f, length(m.swept.diagonal()));
        for (size_t i = 0; i < now.coarse.positions.size() && rigid; i += std::max<size_t>(1, now.coarse.positions.size() / 64))
            rigid = length(delta.point(before.coarse.positions[i]) - now.coarse.positions[i]) <= tolerance;
        if (rigid) m.kind = ObjectMotion::Kind::Rigid, m.delta = delta;
    }
    return m;
}

bool json_differs(const nlohmann::json& a, const nlohmann::json& b, const char* key) {
    return a.value(key, nlohmann::json()) != b.value(key, nlohmann::json());
}

}  // namespace

SceneChanges scene_changes(const Scene& before, const Scene& now) {
    SceneChanges c;
    c.camera = !(before.camera.pose() == now.camera.pose()) || before.camera.width != now.camera.width ||
               before.camera.height != now.camera.height;
    c.comparable = before.objects.size() == now.objects.size() && before.materials.size() == now.materials.size();
    MeshComparisons meshes;
    for (size_t i = 0; c.comparable && i < now.objects.size(); ++i)
        c.comparable = before.objects[i].name == now.objects[i].name && before.objects[i].instance == now.objects[i].instance &&
                       meshes.same_topology(before.objects[i].coarse_mesh(), now.objects[i].coarse_mesh());
    // Cutouts decide where surfaces are: other cutouts are other geometry.
    for (size_t i = 0; c.comparable && i < now.materials.size(); ++i)
        c.comparable = cutout_identity(before.materials[i]) == cutout_identity(now.materials[i]);
    if (!c.comparable) return c;
    c.visible_geometry_same = true;
    for (size_t i = 0; i < now.objects.size(); ++i) {
        const Object &a = before.objects[i], &b = now.objects[i];
        c.objects.push_back(motion_of(a, b, meshes));
        c.visible_geometry_same = c.visible_geometry_same && c.objects.back().kind == ObjectMotion::Kind::Static &&
                                  meshes.same_positions(a.visible_mesh(), b.visible_mesh()) &&
                                  meshes.same_indices(a.visible_mesh(), b.visible_mesh()) && a.material_override == b.material_override;
    }
    // Lights and the sky: their JSON and the files they read (a sky texture).
    c.lights = json_differs(before.description, now.description, "lights") || before.inputs_hash("lights") != now.inputs_hash("lights");
    for (const Light& l : now.lights) c.sky |= l.type == LightType::Sky && c.lights;
    c.materials.assign(now.materials.size(), 0);
    const nlohmann::json mb = before.description.value("materials", nlohmann::json::object()),
                         mn = now.description.value("materials", nlohmann::json::object());
    for (size_t i = 0; i < now.materials.size(); ++i) {
        const Material &a = before.materials[i], &b = now.materials[i];
        const bool albedo = a.name != b.name || !(a.color == b.color) || a.color_texture != b.color_texture;
        c.materials[i] = albedo || json_differs(mb, mn, b.name.c_str());
        // An emissive material that changed is a light that changed.
        if (!(a.emission == b.emission) || a.emission_texture != b.emission_texture) c.lights = true;
    }
    if (before.inputs_hash("materials") != now.inputs_hash("materials")) c.lights = true;  // a texture file changed
    // An emissive object that moves is a light that moves.
    for (size_t i = 0; i < now.objects.size(); ++i)
        if (c.objects[i].kind != ObjectMotion::Kind::Static)
            for (uint32_t m : now.objects[i].coarse.face_materials) c.lights = c.lights || now.materials[m].is_emissive();
    return c;
}

}  // namespace bounce
