#include "bounce/scene/scene_load.h"

#include <OpenImageIO/imageio.h>
#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <filesystem>

#include "bounce/core/error.h"
#include "bounce/core/files.h"
#include "bounce/core/random.h"
#include "bounce/scene/json_reader.h"
#include "bounce/dice/displacement.h"
#include "bounce/scene/fur_reader.h"
#include "bounce/scene/mesh_import.h"
#include "bounce/scene/params.h"

namespace bounce {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

std::shared_ptr<const LatLongMap> load_latlong(const std::string& path, const JsonReader& r,
                                               const std::string& key) {
    auto in = OIIO::ImageInput::open(path);
    if (!in) r.fail(key, "cannot read image \"" + path + "\": " + OIIO::geterror());
    const OIIO::ImageSpec& spec = in->spec();
    auto map = std::make_shared<LatLongMap>();
    map->width = spec.width;
    map->height = spec.height;
    std::vector<float> all(static_cast<size_t>(spec.width) * spec.height * spec.nchannels);
    if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, all.data()))
        r.fail(key, "cannot read image \"" + path + "\": " + in->geterror());
    map->rgb.resize(static_cast<size_t>(spec.width) * spec.height * 3);
    for (size_t i = 0; i < static_cast<size_t>(spec.width) * spec.height; ++i)
        for (int c = 0; c < 3; ++c)
            map->rgb[3 * i + c] = all[i * spec.nchannels + std::min(c, spec.nchannels - 1)];
    return map;
}

Transform read_transform(const JsonReader& obj) {
    if (!obj.has("transform")) return {};
    JsonReader t(obj.raw("transform"), obj.at("transform"), obj.ctx(), {"translate", "rotate", "scale", "matrix"});
    if (t.has("matrix")) {
        if (t.has("translate") || t.has("rotate") || t.has("scale"))
            t.fail("matrix", "\"matrix\" cannot be combined with translate/rotate/scale");
        const json& m = t.raw("matrix");
        if (!m.is_array() || m.size() != 16) t.fail("matrix", "expected an array of 16 numbers (row-major)");
        Transform r;
        for (size_t i = 0; i < 16; ++i)
            r.m[i] = static_cast<float>(t.check_number(m[i], t.at("matrix") + "/" + std::to_string(i), -INFINITY, INFINITY));
        return r;
    }
    Transform r;
    if (t.has("translate")) r = Transform::translate(t.vec3("translate", {}));
    if (t.has("rotate")) {
        const json& rot = t.raw("rotate");
        if (!rot.is_array() || rot.size() != 4)
            t.fail("rotate", "expected [degrees, axis_x, axis_y, axis_z]");
        float v[4];
        for (size_t i = 0; i < 4; ++i)
            v[i] = static_cast<float>(t.check_number(rot[i], t.at("rotate") + "/" + std::to_string(i), -INFINITY, INFINITY));
        Vec3 axis{v[1], v[2], v[3]};
        if (length(axis) == 0) t.fail("rotate", "rotation axis is zero");
        r = r * Transform::rotate(v[0], axis);
    }
    if (t.has("scale")) {
        const json& s = t.raw("scale");
        Vec3 sc = s.is_number() ? Vec3(static_cast<float>(t.check_number(s, t.at("scale"), -INFINITY, INFINITY)))
                                : t.vec3("scale", {});
        if (sc.x == 0 || sc.y == 0 || sc.z == 0) t.fail("scale", "scale must not be zero");
        r = r * Transform::scale(sc);
    }
    return r;
}

int material_index(const Scene& scene, const std::string& name) {
    for (size_t i = 0; i < scene.materials.size(); ++i)
        if (scene.materials[i].name == name) return static_cast<int>(i);
    return -1;
}


Material read_material(const JsonReader& m, const std::string& name) {
    Material mat;
    mat.name = name;
    mat.color = m.color("color", Color(0.7f));
    for (int i = 0; i < 3; ++i)
        if (mat.color[i] > 1) m.fail("color", "albedo components must be <= 1 (energy conservation)");
    mat.color_texture = m.file("color_texture", false);
    mat.emission = m.color("emission", Color(0));
    mat.specular = m.color("specular", Color(0));
    for (int i = 0; i < 3; ++i)
        if (mat.specular[i] > 1) m.fail("specular", "specular components must be <= 1");
    mat.roughness = static_cast<float>(m.number("roughness", mat.roughness, 0.01, 1));
    mat.bump_texture = m.file("bump_texture", false);
    mat.ao_texture = m.file("ao_texture", false);
    mat.normal_texture = m.file("normal_texture", false);
    mat.bump_strength = static_cast<float>(m.number("bump_strength", mat.bump_strength, -1e3, 1e3));
    return mat;
}

Light read_light(const JsonReader& r, const Scene& scene) {
    std::string type = r.choice("type", "", {"point", "spot", "distant", "quad", "sky"});
    Light l;
    l.color = r.color("color", Color(1)) * r.number("intensity", 1, 0, kMaxRadiometric);
    for (int i = 0; i < 3; ++i)
        if (!(l.color[i] <= kMaxRadiometric)) r.fail("intensity", fmt::format("color x intensity exceeds {:g}", kMaxRadiometric));
    if (type == "point" || type == "spot") {
        l.type = type == "point" ? LightType::Point : LightType::Spot;
        l.position = r.vec3("position", {}, true);
        if (type == "spot") {
            l.direction = r.vec3("direction", {0, -1, 0});
            if (length(l.direction) == 0) r.fail("direction", "direction is zero");
            l.direction = normalize(l.direction);
            l.cone_angle = static_cast<float>(r.number("cone_angle", 30, 0, 90));
            l.cone_falloff = static_cast<float>(r.number("cone_falloff", 5, 0, 90));
        }
    } else if (type == "distant") {
        l.type = LightType::Distant;
        l.direction = r.vec3("direction", {}, true);
        if (length(l.direction) == 0) r.fail("direction", "direction is zero");
        l.direction = normalize(l.direction);
    } else if (type == "quad") {
        l.type = LightType::Quad;
        l.corner = r.vec3("corner", {}, true);
        l.edge_u = r.vec3("edge_u", {}, true);
        l.edge_v = r.vec3("edge_v", {}, true);
        if (length(cross(l.edge_u, l.edge_v)) == 0) r.fail("edge_v", "quad light has zero area");
    } else {
        l.type = LightType::Sky;
        l.sky_rotation = static_cast<float>(r.number("rotation", 0));
        std::string tex = r.file("texture", false);
        if (!tex.empty()) l.sky_map = load_latlong(tex, r, "texture");
    }
    (void)scene;
    return l;
}

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

/// A mesh object with "subdivision": its control mesh diced into the fine tessellation (from
/// the camera, render.dicing) and the coarse one (render.dicing.ray_level), both displaced
/// when the object has a "displacement".
void read_subdivision_object(const JsonReader& r, Scene& scene, int mat, Object& obj, SubdivScheme scheme) {
    SubdivSurface surf;
    surf.scheme = scheme;
    surf.boundary = r.choice("boundary", "edge-and-corner", {"edge-only", "edge-and-corner"}) == "edge-only"
                        ? SubdivBoundary::EdgeOnly : SubdivBoundary::EdgeAndCorner;
    if (r.has("fine_subdivisions")) r.fail("fine_subdivisions", "a subdivision surface is diced by render.dicing, not fine_subdivisions");
    const std::string file = r.file("file", true);
    try {
        surf.control = load_control_mesh(file, obj.name, scene.materials, mat, read_transform(r));
        check_control_mesh(surf.control, surf.scheme);
    } catch (const InputError& e) {
        r.fail("file", e.what());
    }
    if (r.has("displacement")) {
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
    const DicingSettings& ds = scene.render.dicing;
    const int ray_level = std::min(ds.ray_level, ds.max_level);
    const int level = dicing_level(surf.control, [&](const Vec3& p) { return pixels_per_unit(scene.camera, p); },
                                   ds.shading_rate, ray_level, ds.max_level);
    // The fine tessellation per control edge: about shading_rate pixels per diced edge from the
    // camera, never coarser than the ray tessellation (docs/displacement.md).
    const auto rate = [&](const Vec3& a, const Vec3& b) {
        const float px = projected_pixels(scene.camera, a, b) / ds.shading_rate;
        return static_cast<int>(std::clamp(std::round(px), static_cast<float>(1 << ray_level), static_cast<float>(1 << ds.max_level)));
    };
    // Refuse a dicing that cannot fit before allocating it: per face its largest edge rate
    // squared (twice for quads, half per corner for n-gons), and the ray tessellation.
    double micropolygons = 0;
    int largest = 1 << ray_level;
    for (size_t f = 0, k = 0; f < surf.control.face_count(); k += static_cast<size_t>(surf.control.face_sizes[f++])) {
        const int n = surf.control.face_sizes[f];
        int rmax = 1;
        for (int i = 0; i < n; ++i)
            rmax = std::max(rmax, rate(surf.control.positions[static_cast<size_t>(surf.control.face_vertices[k + static_cast<size_t>(i)])],
                                       surf.control.positions[static_cast<size_t>(surf.control.face_vertices[k + static_cast<size_t>((i + 1) % n)])]));
        largest = std::max(largest, rmax);
        const double cells = static_cast<double>(rmax) * rmax, coarse = std::pow(4.0, ray_level);
        micropolygons += (n == 3 ? 1.0 : n == 4 ? 2.0 : n / 2.0) * (cells + coarse);
    }
    if (micropolygons > kMaxMicropolygons)
        r.fail("", fmt::format("dicing {} gives {:.3g} micropolygons (about {:.0f} GiB); the limit is {:.0e}: raise "
                               "render.shading_rate or lower render.max_level / render.ray_level",
                               obj.name, micropolygons, micropolygons * 150 / (1 << 30), kMaxMicropolygons));
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
        obj.displacement_bound = std::abs(surf.displacement.scale) *
                                 std::max(std::abs(surf.displacement.midpoint), std::abs(1 - surf.displacement.midpoint));
    obj.dicing_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    obj.surface = std::make_shared<const SubdivSurface>(std::move(surf));
}

void read_object(const JsonReader& r, Scene& scene, size_t index) {
    Object obj;
    obj.name = r.string("name", fmt::format("object{}", index));
    std::string type = r.choice("type", r.has("file") ? "mesh" : "", {"mesh", "quad", "sphere"});
    int mat = -1;
    if (r.has("material")) {
        std::string name = r.string("material", "");
        mat = material_index(scene, name);
        if (mat < 0) {
            std::vector<std::string> names;
            for (const auto& m : scene.materials) names.push_back(m.name);
            std::string hint = closest_match(name, names);
            r.fail("material", fmt::format("unknown material \"{}\"{}", name,
                                           hint.empty() ? "" : " (did you mean \"" + hint + "\"?)"));
        }
    }
    auto default_material = [&]() {
        if (mat >= 0) return static_cast<uint32_t>(mat);
        int d = material_index(scene, "default");
        if (d < 0) {
            Material m;
            m.name = "default";
            scene.materials.push_back(m);
            d = static_cast<int>(scene.materials.size() - 1);
        }
        return static_cast<uint32_t>(d);
    };
    int fine = 0;
    const std::string subdivision = r.choice("subdivision", "none", {"none", "catmull-clark", "loop"});
    if (type == "mesh" && subdivision != "none") {
        read_subdivision_object(r, scene, mat, obj, subdivision == "loop" ? SubdivScheme::Loop : SubdivScheme::CatmullClark);
    } else if (type == "mesh") {
        std::string file = r.file("file", true);
        fine = r.integer("fine_subdivisions", 0, 0, 6);
        try {
            obj.coarse = load_mesh_file(file, obj.name, scene.materials, mat);
        } catch (const InputError& e) {
            r.fail("file", e.what());
        }
        obj.coarse.transform(read_transform(r));
        if (fine > 0) obj.fine = subdivide_linear(obj.coarse, fine);
    } else if (type == "quad") {
        const json& v = r.has("vertices") ? r.raw("vertices") : json();
        if (!v.is_array() || v.size() != 4) r.fail(r.has("vertices") ? "vertices" : "", "a quad needs \"vertices\": four [x,y,z] points");
        Vec3 p[4];
        for (size_t i = 0; i < 4; ++i) p[i] = r.to_vec3(v[i], r.at("vertices") + "/" + std::to_string(i));
        if (length(cross(p[1] - p[0], p[2] - p[0])) == 0) r.fail("vertices", "quad is degenerate (zero area)");
        fine = r.integer("fine_subdivisions", 0, 0, 8);
        obj.coarse = make_quad(p[0], p[1], p[2], p[3], default_material());
        obj.coarse.transform(read_transform(r));
        if (fine > 0) obj.fine = subdivide_linear(obj.coarse, fine);
    } else {
        Vec3 c = r.vec3("center", {});
        auto radius = static_cast<float>(r.number("radius", 1, 0, kMaxCoordinate));
        if (radius <= 0) r.fail("radius", "radius must be > 0");
        int level = r.integer("subdivisions", 3, 0, 8);
        fine = r.integer("fine_subdivisions", 2, 0, 8 - level);
        uint32_t m = default_material();
        obj.coarse = make_icosphere(c, radius, level, m);
        Transform t = read_transform(r);
        obj.coarse.transform(t);
        if (fine > 0) {
            obj.fine = make_icosphere(c, radius, level + fine, m);
            obj.fine.transform(t);
        }
    }
    if (obj.coarse.triangle_count() == 0) r.fail(type == "mesh" ? "file" : "", "mesh has no triangles");
    for (const auto& p : obj.coarse.positions)
        if (!isfinite(p) || std::fabs(p.x) > kMaxCoordinate || std::fabs(p.y) > kMaxCoordinate || std::fabs(p.z) > kMaxCoordinate)
            r.fail("", fmt::format("mesh has vertex positions that are not finite or beyond +-{:g} (after the transform)", kMaxCoordinate));
    if (r.has("fur")) obj.fur = read_fur(JsonReader(r.raw("fur"), r.at("fur"), r.ctx(), fur_keys()), obj.visible(), scene);
    scene.objects.push_back(std::move(obj));
}


/// Reads one section's rows of the parameter table ("camera", "render"): keys not in the table
/// are errors with a suggestion, every value is checked as the type it is used in.
void read_params(const json& j, const std::string& section, Scene& scene, const JsonContext& ctx) {
    const ParamTable& table = scene_params();
    std::vector<std::string> allowed;
    for (const Param& p : table)
        if (p.section() == section) allowed.push_back(p.name());
    JsonReader r(j, "/" + section, ctx, allowed);
    for (const Param& p : table) {
        if (p.section() != section) continue;
        if (!r.has(p.name())) {
            if (p.required) r.fail("", fmt::format("missing required key \"{}\"", p.name()));
            continue;
        }
        const std::string ptr = r.at(p.name());
        json v = check_param(p, r.raw(p.name()), [&](const std::string& sub, const std::string& msg) { ctx.fail(ptr + sub, msg); });
        if (p.type == ParamType::Path && !v.get<std::string>().empty() && fs::path(v.get<std::string>()).is_relative() &&
            !ctx.from_command_line(ptr))
            v = (ctx.dir / v.get<std::string>()).string();
        p.set(scene, v);
    }
}

Scene build_scene(json doc, const std::string& path, const std::vector<Override>& overrides) {
    JsonContext ctx;
    ctx.file = path;
    ctx.dir = fs::path(path).parent_path();
    if (!doc.is_object()) ctx.fail("", fmt::format("expected an object at the top of the scene, got {}", json_type_name(doc)));
    for (const auto& o : overrides) ctx.cli_origins[apply_override(doc, o)] = o.origin;

    Scene scene;
    scene.path = path;
    scene.description = doc;
    JsonReader root(doc, "", ctx, {"camera", "render", "materials", "lights", "objects", "description"});

    if (root.has("render")) read_params(root.raw("render"), "render", scene, ctx);
    if (!root.has("camera")) root.fail("", "missing required key \"camera\"");
    read_params(root.raw("camera"), "camera", scene, ctx);
    const Camera& cam = scene.camera;
    if (length(cam.look_at - cam.position) == 0) ctx.fail("/camera/look_at", "look_at equals position");
    if (length(cross(cam.look_at - cam.position, cam.up)) == 0) ctx.fail("/camera/up", "up is parallel to the view direction");
    const CacheSettings& cs = scene.render.cache;
    if (cs.max_spacing < cs.min_spacing) ctx.fail("/render/max_spacing", "max_spacing is below min_spacing");
    const auto& crop = scene.render.visibility.crop;
    if (scene.render.visibility.has_crop() &&
        (crop[0] >= crop[1] || crop[2] >= crop[3] || crop[1] > cam.width || crop[3] > cam.height))
        ctx.fail("/render/crop", fmt::format("crop [{}, {}, {}, {}] is empty or outside the {}x{} image",
                                            crop[0], crop[1], crop[2], crop[3], cam.width, cam.height));

    // Materials.
    if (root.has("materials")) {
        const json& mats = root.raw("materials");
        if (!mats.is_object()) root.fail("materials", "expected an object of named materials");
        for (auto it = mats.begin(); it != mats.end(); ++it) {
            JsonReader m(it.value(), "/materials/" + it.key(), ctx, {"color", "color_texture", "emission", "specular", "roughness",
                                                                     "bump_texture", "normal_texture", "bump_strength", "ao_texture"});
            scene.materials.push_back(read_material(m, it.key()));
        }
    }

    // Objects.
    if (!root.has("objects")) root.fail("", "missing required key \"objects\"");
    const json& objs = root.raw("objects");
    if (!objs.is_array() || objs.empty()) root.fail("objects", "expected a non-empty array of objects");
    for (size_t i = 0; i < objs.size(); ++i) {
        JsonReader o(objs[i], fmt::format("/objects/{}", i), ctx,
                     {"name", "type", "file", "material", "transform", "fine_subdivisions", "vertices", "center", "radius",
                      "subdivisions", "subdivision", "boundary", "displacement", "fur"});
        read_object(o, scene, i);
    }

    // Lights: explicit ones, then one mesh light per object with emissive faces.
    if (root.has("lights")) {
        const json& ls = root.raw("lights");
        if (!ls.is_array()) root.fail("lights", "expected an array of lights");
        for (size_t i = 0; i < ls.size(); ++i) {
            JsonReader l(ls[i], fmt::format("/lights/{}", i), ctx,
                         {"type", "color", "intensity", "position", "direction", "cone_angle", "cone_falloff", "corner", "edge_u",
                          "edge_v", "texture", "rotation", "name"});
            scene.lights.push_back(read_light(l, scene));
        }
    }
    for (size_t i = 0; i < scene.objects.size(); ++i) {
        bool emits = false;
        for (uint32_t m : scene.objects[i].coarse.face_materials) emits |= scene.materials[m].is_emissive();
        if (emits) {
            Light l;
            l.type = LightType::Mesh;
            l.object = static_cast<uint32_t>(i);
            scene.lights.push_back(l);
        }
    }
    return scene;
}

}  // namespace

Scene load_scene_text(const std::string& text, const std::string& path, const std::vector<Override>& overrides) {
    return build_scene(parse_json_text(text, path), path, overrides);
}

Scene load_scene(const std::string& path, const std::vector<Override>& overrides) {
    std::string ext = fs::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
    if (ext == ".json") return load_scene_text(read_text_file(path), path, overrides);
    check_input_file(path);
    return build_scene(describe_mesh_file(path), path, overrides);
}

Bounds Scene::bounds() const {
    Bounds b;
    for (const auto& o : objects) b.extend(o.coarse.bounds());
    return b;
}

uint64_t Scene::fingerprint(const std::vector<std::string>& parts, bool without_surface_shading) const {
    uint64_t h = 0x243f6a8885a308d3ULL;
    for (const auto& part : parts) {
        json value = description.contains(part) ? description[part] : json();
        if (without_surface_shading && part == "materials" && value.is_object())
            for (auto& [name, m] : value.items())
                if (m.is_object())
                    for (const char* key : {"specular", "roughness", "bump_texture", "normal_texture", "bump_strength", "ao_texture"})
                        m.erase(key);
        std::string s = part + "=" + (value.is_null() ? "" : value.dump());
        for (unsigned char c : s) h = hash_combine(h, c);
    }
    return h;
}

uint64_t Scene::visibility_fingerprint() const {
    Scene copy;
    copy.description = {{"camera", description.value("camera", json())}, {"objects", description.value("objects", json())}};
    for (auto& o : copy.description["objects"])
        if (o.is_object() && o.contains("fur") && o["fur"].is_object())
            for (const std::string& key : fur_lighting_keys()) o["fur"].erase(key);
    // Subdivision surfaces are diced from the camera by render.dicing and fragments name their
    // micropolygons: a deep file of another dicing would shade the wrong ones. ("per-edge": the
    // dicing rule, so files of the earlier uniform dicing are not taken for this one.)
    const bool diced = std::any_of(objects.begin(), objects.end(), [](const Object& o) { return o.surface != nullptr; });
    if (!diced) return copy.fingerprint({"camera", "objects"});
    const DicingSettings& d = render.dicing;
    copy.description["dicing"] = {{"rule", "per-edge"}, {"shading_rate", d.shading_rate}, {"ray_level", d.ray_level},
                                  {"max_level", d.max_level}};
    return copy.fingerprint({"camera", "objects", "dicing"});
}

Color LatLongMap::lookup(const Vec3& d, float rotation_deg) const {
    float u = 0.5f + std::atan2(d.x, -d.z) / (2 * kPi) + rotation_deg / 360.0f;
    u -= std::floor(u);
    float v = std::acos(std::clamp(d.y, -1.0f, 1.0f)) / kPi;
    int x = std::min(width - 1, static_cast<int>(u * static_cast<float>(width)));
    int y = std::min(height - 1, static_cast<int>(v * static_cast<float>(height)));
    const float* p = &rgb[(static_cast<size_t>(y) * width + x) * 3];
    return {p[0], p[1], p[2]};
}

}  // namespace bounce
