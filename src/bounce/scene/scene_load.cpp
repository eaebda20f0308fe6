#include "bounce/scene/scene_load.h"

#include <OpenImageIO/imageio.h>
#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <filesystem>

#include "bounce/core/error.h"
#include "bounce/core/memory.h"
#include "bounce/core/files.h"
#include "bounce/core/random.h"
#include "bounce/scene/fur_reader.h"
#include "bounce/scene/item_readers.h"
#include "bounce/scene/link_reader.h"
#include "bounce/scene/json_reader.h"
#include "bounce/scene/keyframes.h"
#include "bounce/scene/mesh_import.h"
#include "bounce/scene/instance_reader.h"
#include "bounce/scene/object_reader.h"
#include "bounce/config/params.h"

namespace bounce {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

/// Reads one section's rows of the parameter table ("camera", "render"): keys not in the table
/// are errors with a suggestion, every value is checked as the type it is used in.
void read_params(const json& j, const std::string& section, ParamsOut out, std::vector<std::string>& input_folders,
                 const JsonContext& ctx) {
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
        if (p.type == ParamType::Path && !v.get<std::string>().empty()) {
            if (fs::path(v.get<std::string>()).is_relative() && !ctx.relative_to_working_dir(ptr))
                v = (ctx.dir / v.get<std::string>()).string();
            if (ctx.check_path) ctx.check_path(v.get<std::string>(), ptr);
            // A folder the render reads and writes: a file of that name is refused now, not after the render.
            std::error_code ec;
            const auto st = fs::status(v.get<std::string>(), ec);
            if (!ec && st.type() != fs::file_type::not_found && st.type() != fs::file_type::directory)
                ctx.fail(ptr, "\"" + v.get<std::string>() + "\" is not a folder");
            input_folders.push_back(v.get<std::string>());
        }
        p.set(out, v);
    }
}

void check_camera(const Camera& cam, const JsonContext& ctx, const std::string& when = "") {
    if (length(cam.look_at - cam.position) == 0) ctx.fail("/camera/look_at", "look_at equals position" + when);
    if (length(cross(cam.look_at - cam.position, cam.up)) == 0) ctx.fail("/camera/up", "up is parallel to the view direction" + when);
    // A reversed interval would blur over the same times; refused as the typo it most likely is.
    if (cam.shutter[1] < cam.shutter[0])
        ctx.fail("/camera/shutter",
                 fmt::format("the shutter closes ({:g}) before it opens ({:g}){}", cam.shutter[1], cam.shutter[0], when));
}

/// Fur control points moved rigidly (widths kept).
std::vector<float> moved_fur(const Fur& fur, const Transform& move) {
    std::vector<float> v = fur.vertices;
    for (size_t i = 0; i + 3 < v.size(); i += 4) {
        const Vec3 p = move.point({v[i], v[i + 1], v[i + 2]});
        v[i] = p.x, v[i + 1] = p.y, v[i + 2] = p.z;
    }
    return v;
}

/// Motion blur: the camera's pose and the visible mesh of every object whose placement is keyed,
/// at shutter open and close (an object's placement then, applied to its shape now).
void add_shutter_positions(Scene& scene, const JsonContext& ctx) {
    std::array<nlohmann::json, 2> docs;  // the scene at shutter open and close (a file without keys: as it is)
    for (size_t k = 0; k < 2; ++k) {
        docs[k] = scene.keyed.is_object() ? evaluate_keys(scene.keyed, scene.frame + scene.camera.shutter[k], ctx) : scene.description;
        Scene then;  // the camera section alone, checked as the frame's is
        read_params(docs[k]["camera"], "camera", then, then.input_folders, ctx);
        check_camera(then.camera, ctx,
                     fmt::format(" at shutter {} (frame {:g})", k ? "close" : "open", scene.frame + scene.camera.shutter[k]));
        scene.camera.shutter_pose[k] = then.camera.pose();
    }
    for (size_t i = 0; i < scene.objects.size(); ++i) {
        Object& o = scene.objects[i];
        if (!o.moves) continue;
        const Transform undo = o.placement.inverse();
        for (size_t k = 0; k < 2; ++k) {
            const JsonReader r(docs[k]["objects"][i], fmt::format("/objects/{}", i), ctx, object_keys());
            if (o.deforms) {  // a skin or morph: posed again at the shutter's ends, its fur carried there
                const TriangleMesh then = posed_visible_mesh(r, scene, scene.frame + scene.camera.shutter[k]);
                if (o.fur && same_triangles(o.visible(), then)) o.fur_shutter[k] = carried_vertices(*o.fur, o.visible(), then);
                o.shutter[k] = then.positions;
                continue;
            }
            const Transform then = read_transform(r), move = then * undo;
            if (o.fur) o.fur_shutter[k] = moved_fur(*o.fur, move);
            if (o.local_coarse) {  // traced as its local shape placed then: no moved copy of its vertices
                if (!o.shutter_placement) o.shutter_placement.emplace();
                (*o.shutter_placement)[k] = then;
                continue;
            }
            o.shutter[k].clear();
            for (const Vec3& p : o.visible().positions) o.shutter[k].push_back(move.point(p));
        }
        const size_t n = o.visible().positions.size();  // a pose of other vertices is not blurred
        if (o.shutter[0].size() != n || o.shutter[1].size() != n) o.shutter = {};
        if (o.fur_shutter[0].size() != o.fur_shutter[1].size()) o.fur_shutter = {};
    }
}

/// The pointers of every keyed value in `j` (an object with a "keys" array).
void collect_keyed(const json& j, const std::string& ptr, std::vector<std::string>& out) {
    if (j.is_object() && j.contains("keys") && j["keys"].is_array()) return out.push_back(ptr);
    if (j.is_object())
        for (const auto& [k, v] : j.items()) collect_keyed(v, ptr + "/" + k, out);
    else if (j.is_array())
        for (size_t i = 0; i < j.size(); ++i) collect_keyed(j[i], ptr + "/" + std::to_string(i), out);
}

/// The file's own value of every parameter a flag or --set replaces, checked as if no flag
/// were given (each key's value too, for a keyed one): the same file must load in the tool and
/// on a farm that sets no flag.
void check_overridden_values(const json& doc, const std::vector<Override>& overrides, const JsonContext& ctx) {
    for (const Override& o : overrides) {
        const std::string key = o.assignment.substr(0, o.assignment.find('='));
        const Param* p = find_param(scene_params(), key);
        if (!p) continue;
        std::string ptr = "/" + key;
        std::replace(ptr.begin(), ptr.end(), '.', '/');
        const json::json_pointer at(ptr);
        if (!doc.contains(at)) continue;
        const json& v = doc.at(at);
        const auto fail = [&](const std::string& where) {
            return [&ctx, where](const std::string& sub, const std::string& msg) { ctx.fail(where + sub, msg); };
        };
        if (!has_keys(v)) {
            check_param(*p, v, fail(ptr));
            continue;
        }
        // A keyed value the flag replaces is refused as it would be without the flag.
        if (!p->animatable) ctx.fail(ptr, "this value cannot be animated (bounce params lists what can: the \"animatable\" column)");
        const json& keys = v.value("keys", json());
        for (size_t i = 0; keys.is_array() && i < keys.size(); ++i)
            if (keys[i].is_array() && keys[i].size() == 2) check_param(*p, keys[i][1], fail(fmt::format("{}/keys/{}/1", ptr, i)));
    }
}

/// render.max_spacing against min_spacing, and a crop inside the image.
void check_frame_settings(const Camera& cam, const RenderSettings& render, const JsonContext& ctx) {
    const CacheSettings& cs = render.cache;
    if (cs.max_spacing < cs.min_spacing) ctx.fail("/render/max_spacing", "max_spacing is below min_spacing");
    const auto& crop = render.visibility.crop;
    // Only all zeros means the full frame: [4, 4, 4, 4] is an empty window, not no crop.
    const bool crop_given = crop[0] != 0 || crop[1] != 0 || crop[2] != 0 || crop[3] != 0;
    if (crop_given && (crop[0] >= crop[1] || crop[2] >= crop[3] || crop[1] > cam.width || crop[3] > cam.height))
        ctx.fail("/render/crop", fmt::format("crop [{}, {}, {}, {}] is empty or outside the {}x{} image", crop[0], crop[1], crop[2],
                                             crop[3], cam.width, cam.height));
}

/// Every object: instancers last (their prototypes may come after them), each holding its index
/// meanwhile; then the meshes a mesh file's nodes share.
void read_objects(const JsonReader& root, Scene& scene, const DicingSettings& dicing, const JsonContext& ctx) {
    if (!root.has("objects")) root.fail("", "missing required key \"objects\"");
    const json& objs = root.raw("objects");
    if (!objs.is_array() || objs.empty()) root.fail("objects", "expected a non-empty array of objects");
    check_generated_geometry(root, objs, dicing);
    // Instancers last (their prototypes may come after them), each holding its index meanwhile.
    std::vector<Object> file_instances;  // meshes shared by a mesh file's nodes, after every entry
    for (size_t i = 0; i < objs.size(); ++i) {
        if (places_instances(objs[i]))
            scene.objects.emplace_back().instance = true;
        else
            read_object(JsonReader(objs[i], fmt::format("/objects/{}", i), ctx, object_keys()), scene, dicing, i, file_instances);
    }
    // Room for every placement at once: a vector of Objects that grew as they came would move
    // them all at each doubling (most of a 14 400-placement scene's load).
    double placements = static_cast<double>(file_instances.size());
    for (const json& o : objs) placements += static_cast<double>(placements_of(o));
    if (memory_shortfall((placements + static_cast<double>(scene.objects.size())) * sizeof(Object), "").empty())
        reserve_huge(scene.objects, scene.objects.size() + static_cast<size_t>(placements));
    for (size_t i = 0; i < objs.size(); ++i)
        if (places_instances(objs[i]))
            read_instances(JsonReader(objs[i], fmt::format("/objects/{}", i), ctx, object_keys()), objs, scene, i, file_instances);
    reserve_huge(scene.objects, scene.objects.size() + file_instances.size());
    for (Object& o : file_instances) scene.objects.push_back(std::move(o));
}

/// Explicit lights, then one mesh light per object with emissive faces.
void read_lights(const JsonReader& root, Scene& scene, const JsonContext& ctx) {
    if (root.has("lights")) {
        const json& ls = root.raw("lights");
        if (!ls.is_array()) root.fail("lights", "expected an array of lights");
        int shadow_slots = 0;
        for (size_t i = 0; i < ls.size(); ++i) {
            JsonReader l(ls[i], fmt::format("/lights/{}", i), ctx, light_keys());
            scene.lights.push_back(read_light(l));
            scene.lights.back().name = l.string("name", fmt::format("light{}", i));
            read_light_links(l, scene, scene.lights.back(), shadow_slots);
        }
    }
    for (size_t i = 0; i < scene.objects.size(); ++i) {
        bool emits = false;  // (an instance may not emit: instance_reader refuses it; a prototype is not placed)
        for (uint32_t m : scene.objects[i].placed() ? scene.objects[i].coarse.face_materials : std::vector<uint32_t>{})
            emits |= scene.materials[m].is_emissive();
        if (emits) {
            Light l;
            l.type = LightType::Mesh;
            l.object = static_cast<uint32_t>(i);
            l.name = scene.objects[i].name;
            scene.lights.push_back(l);
        }
    }
}

Scene build_scene(json doc, const std::string& path, const std::vector<Override>& overrides, const LoadOptions& options) {
    JsonContext ctx;
    ctx.file = path;
    ctx.dir = fs::path(path).parent_path();
    ctx.check_path = options.check_path;
    ctx.resources = options.resources;
    if (!doc.is_object()) ctx.fail("", fmt::format("expected an object at the top of the scene, got {}", json_type_name(doc)));
    check_overridden_values(doc, overrides, ctx);
    for (const auto& o : overrides) ctx.overridden.insert_or_assign(apply_override(doc, o), o);

    Scene scene;
    scene.path = path;
    // Time: the shot, and every keyed value at the frame (keyframes.h); then a plain scene.
    scene.shot = read_shot(doc, ctx);
    scene.frame = options.frame.value_or(scene.shot.first);
    if (scene.shot.animated && !scene.shot.contains(scene.frame))
        throw InputError(options.frame_origin.empty() ? path : "command line",
                         options.frame_origin.empty() ? "/animation/frames" : options.frame_origin, scene.shot.outside(scene.frame));
    if (has_keys(doc)) {
        scene.keyed = doc;
        doc = evaluate_keys(doc, scene.frame, ctx);
        collect_keyed(scene.keyed, "", ctx.keyed);
        ctx.frame = scene.frame;
    }
    scene.description = std::move(doc);  // (read in place: a copy was a 14 400-placement scene's second parse)
    ctx.inputs = &scene.inputs;
    JsonReader root(scene.description, "", ctx, {"camera", "render", "materials", "lights", "objects", "description", "animation"});

    // The file's render section: the loader hands each reader its part (the dicing), and the
    // scene keeps the whole for the plan.
    RenderSettings render;
    if (root.has("render")) read_params(root.raw("render"), "render", ParamsOut{scene.camera, render}, scene.input_folders, ctx);
    if (!root.has("camera")) root.fail("", "missing required key \"camera\"");
    read_params(root.raw("camera"), "camera", ParamsOut{scene.camera, render}, scene.input_folders, ctx);
    check_camera(scene.camera, ctx);
    check_frame_settings(scene.camera, render, ctx);
    scene.render = render;

    // Materials.
    if (root.has("materials")) {
        const json& mats = root.raw("materials");
        if (!mats.is_object()) root.fail("materials", "expected an object of named materials");
        for (auto it = mats.begin(); it != mats.end(); ++it) {
            JsonReader m(it.value(), "/materials/" + it.key(), ctx, material_keys());
            scene.materials.push_back(read_material(m, it.key()));
        }
    }

    read_objects(root, scene, render.dicing, ctx);

    read_lights(root, scene, ctx);
    if (scene.camera.has_motion_blur()) add_shutter_positions(scene, ctx);
    // What every file holds goes into the identities (deep and cache files).
    ctx.inputs = nullptr;
    for (SceneInput& in : scene.inputs) in.hash = file_content_hash(in.path, ctx.resources.hashes.get());
    return scene;
}

}  // namespace

Scene load_scene_text(const std::string& text, const std::string& path, const std::vector<Override>& overrides,
                      const LoadOptions& options) {
    return build_scene(parse_json_text(text, path), path, overrides, options);
}

Scene load_scene(const std::string& path, const std::vector<Override>& overrides, const LoadOptions& options) {
    const auto start = std::chrono::steady_clock::now();
    Scene scene;
    try {
        if (lower_extension(path) == ".json") {
            // Its text, then its JSON document: 5 to 10 bytes for each byte of the file (measured:
            // 8 MB of placements' JSON took 40 MB; 277 MB of short ones passed 2.6 GB unfinished).
            std::error_code ec;
            const double bytes = static_cast<double>(std::filesystem::file_size(path, ec));
            if (!ec) check_memory(10 * bytes, path, "", fmt::format("reading its {:.0f} MB of JSON", bytes / 1e6));
            scene = load_scene_text(read_text_file(path), path, overrides, options);
        } else {
            check_input_file(path);
            scene = build_scene(describe_mesh_file(path), path, overrides, options);
        }
    } catch (const std::bad_alloc&) {
        // What slipped past the estimates: said with the file, not as a crash.
        throw InputError(path, "",
                         fmt::format("out of memory while loading it ({:.2f} GiB available); fewer placements, objects or "
                                     "texels would fit",
                                     available_memory_bytes() / 1073741824.0));
    }
    scene.load_times.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return scene;
}

Bounds Scene::bounds() const {
    Bounds b;
    for (const auto& o : objects)
        if (o.placed()) b.extend(o.coarse_bounds());
    return b;
}

bool Scene::objects_move() const {
    return std::any_of(objects.begin(), objects.end(), [](const Object& o) { return o.moves; });
}

float Scene::size() const {
    Bounds still;
    for (const auto& o : objects)
        if (!o.moves && o.placed()) still.extend(o.coarse_bounds());
    return length((still.empty() ? bounds() : still).diagonal());
}

Bounds Scene::visible_bounds() const {
    Bounds b = bounds();
    for (const auto& o : objects) {
        if (o.has_fine() && o.placed()) b.extend(o.visible_mesh_bounds());
        if (!o.fur) continue;
        const std::vector<float>& v = o.fur->vertices;
        for (size_t i = 0; i + 3 < v.size() + 1; i += 4) b.extend(Vec3{v[i], v[i + 1], v[i + 2]});
    }
    return b;
}

uint64_t Scene::fingerprint(const std::vector<std::string>& parts, bool without_surface_shading) const {
    uint64_t h = 0x243f6a8885a308d3ULL;
    for (const auto& part : parts) {
        json value = description.contains(part) ? description[part] : json();
        if (without_surface_shading && part == "materials" && value.is_object())
            for (auto& [name, m] : value.items())
                if (m.is_object())
                    for (const std::string& key : surface_shading_keys()) m.erase(key);
        std::string s = part + "=" + (value.is_null() ? "" : value.dump());
        for (unsigned char c : s) h = hash_combine(h, c);
        h = hash_combine(h, inputs_hash(part, without_surface_shading));
    }
    return h;
}

uint64_t Scene::unscaled_fingerprint() const {
    uint64_t h = fingerprint({"objects", "materials"}, true);
    json unscaled = description.contains("lights") ? description["lights"] : json();
    if (unscaled.is_array())
        for (json& l : unscaled)
            if (l.is_object()) l.erase("color"), l.erase("intensity");
    const std::string s = "lights=" + (unscaled.is_null() ? "" : unscaled.dump());
    for (unsigned char c : s) h = hash_combine(h, c);
    return hash_combine(h, inputs_hash("lights", true));
}

std::vector<std::string> Scene::input_paths() const {
    std::vector<std::string> out{path};
    for (const SceneInput& in : inputs) out.push_back(in.path);
    return out;
}

uint64_t Scene::inputs_hash(const std::string& part, bool without_surface_shading) const {
    static const std::vector<std::string> shading_only = {"/bump_texture", "/normal_texture", "/ao_texture"};
    const std::string prefix = "/" + part + "/";
    uint64_t h = 0;
    for (const SceneInput& in : inputs) {
        if (in.pointer.rfind(prefix, 0) != 0) continue;
        if (without_surface_shading &&
            std::any_of(shading_only.begin(), shading_only.end(), [&](const std::string& k) { return in.pointer.ends_with(k); }))
            continue;
        for (unsigned char c : in.pointer) h = hash_combine(h, c);
        h = hash_combine(h, in.hash);
    }
    return h;
}

namespace {

uint64_t hash_floats(uint64_t h, const float* v, size_t n) {
    static_assert(sizeof(Vec3) == 3 * sizeof(float));
    for (size_t i = 0; i < n; ++i) h = hash_combine(h, std::bit_cast<uint32_t>(v[i]));
    return hash_combine(h, n);
}

/// The shape a deforming object has at the frame: what the camera sees (and its shutter's
/// open and close poses, and its fur).
uint64_t pose_hash(const Object& o) {
    const TriangleMesh& m = o.visible();
    uint64_t h = hash_floats(0x9e3779b97f4a7c15ULL, reinterpret_cast<const float*>(m.positions.data()), m.positions.size() * 3);
    for (const std::vector<Vec3>& s : o.shutter) h = hash_floats(h, reinterpret_cast<const float*>(s.data()), s.size() * 3);
    if (o.fur) h = hash_floats(h, o.fur->vertices.data(), o.fur->vertices.size());
    for (const std::vector<float>& f : o.fur_shutter) h = hash_floats(h, f.data(), f.size());
    return h;
}

}  // namespace

uint64_t Scene::visibility_fingerprint() const {
    Scene copy;
    copy.inputs = inputs;
    copy.description = {{"camera", description.value("camera", json())}, {"objects", description.value("objects", json())}};
    if (camera.moves_in_shutter() && copy.description["camera"].is_object()) {
        // A camera keyed to move in the shutter: the same pose at the frame can blur otherwise.
        json poses = json::array();
        for (const Camera::Pose& p : camera.shutter_pose)
            poses.push_back(
                {p.position.x, p.position.y, p.position.z, p.look_at.x, p.look_at.y, p.look_at.z, p.up.x, p.up.y, p.up.z, p.fov});
        copy.description["camera"]["shutter poses"] = poses;
    }
    for (auto& o : copy.description["objects"])
        if (o.is_object() && o.contains("fur") && o["fur"].is_object())
            for (const std::string& key : fur_lighting_keys()) o["fur"].erase(key);
    // A skin or morph targets: the file and its clip name are the same at every frame, the
    // shape the camera sees is not. Each deforming object's pose is part of the identity.
    json poses = json::array();
    for (const Object& o : objects)
        if (o.deforms) poses.push_back(fmt::format("{:016x}", pose_hash(o)));
    if (!poses.empty()) copy.description["objects"] = {{"list", copy.description["objects"]}, {"poses", poses}};
    // Subdivision surfaces are diced from the camera by render.dicing and fragments name their
    // micropolygons: a deep file of another dicing would shade the wrong ones. ("per-edge": the
    // dicing rule, so files of the earlier uniform dicing are not taken for this one.)
    // Cutouts decide what the camera sees: the scene file's cutout keys and opacity textures
    // (a mesh file's materials come with its objects' inputs).
    std::vector<std::string> parts = {"camera", "objects"};
    if (std::any_of(materials.begin(), materials.end(), [](const Material& m) { return m.is_cutout(); })) {
        json cut = json::object();
        const json given = description.value("materials", json::object());
        for (const auto& [name, m] : given.items())
            for (const char* key : {"alpha_mode", "opacity", "opacity_texture", "alpha_cutoff"})
                if (m.is_object() && m.contains(key)) cut[name][key] = m[key];
        copy.description["materials"] = cut;
        std::erase_if(copy.inputs, [](const SceneInput& in) {
            return in.pointer.starts_with("/materials/") && !in.pointer.ends_with("/opacity_texture");
        });
        parts.push_back("materials");
    }
    const bool diced = std::any_of(objects.begin(), objects.end(), [](const Object& o) { return o.surface != nullptr; });
    if (!diced) return copy.fingerprint(parts);
    const DicingSettings& d = render.dicing;
    copy.description["dicing"] = {
        {"rule", "per-edge"}, {"shading_rate", d.shading_rate}, {"ray_level", d.ray_level}, {"max_level", d.max_level}};
    parts.push_back("dicing");
    return copy.fingerprint(parts);
}

Color LatLongMap::at_uv(float u, float v) const {
    const int x = std::clamp(static_cast<int>(u * static_cast<float>(width)), 0, width - 1);
    const int y = std::clamp(static_cast<int>(v * static_cast<float>(height)), 0, height - 1);
    const float* p = &rgb[(static_cast<size_t>(y) * width + x) * 3];
    return {p[0], p[1], p[2]};
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
