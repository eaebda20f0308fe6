#include "bounce/scene/item_readers.h"
#include "bounce/scene/opacity.h"
#include "bounce/scene/surface_textures.h"

#include <OpenImageIO/imageio.h>
#include <fmt/format.h>

#include <cmath>
#include <map>

#include "bounce/core/error.h"
#include "bounce/core/image.h"
#include "bounce/core/image_input.h"
#include "bounce/core/memory.h"

namespace bounce {

using nlohmann::json;

namespace {

constexpr double kDefaultIntensity = 1;

json to_json(const Vec3& v) { return {v.x, v.y, v.z}; }

}  // namespace

json material_defaults() {
    const Material m;
    return {{"color", to_json(m.color)},
            {"emission", to_json(m.emission)},
            {"specular", to_json(m.specular)},
            {"roughness", m.roughness},
            {"bump_strength", m.bump_strength},
            {"mirror", to_json(m.mirror)},
            {"transmission", to_json(m.transmission)},
            {"ior", m.ior},
            {"absorption", to_json(m.absorption)}};
}

const std::vector<std::string>& material_keys() {
    static const std::vector<std::string> keys = {"color",
                                                  "color_texture",
                                                  "emission",
                                                  "specular",
                                                  "roughness",
                                                  "bump_texture",
                                                  "normal_texture",
                                                  "bump_strength",
                                                  "ao_texture",
                                                  "mirror",
                                                  "transmission",
                                                  "ior",
                                                  "absorption",
                                                  "alpha_mode",
                                                  "opacity",
                                                  "opacity_texture",
                                                  "alpha_cutoff",
                                                  "emission_texture",
                                                  "metallic_roughness_texture",
                                                  "metallic",
                                                  "uv_transform",
                                                  "diffuse_transmission",
                                                  "diffuse_transmission_color"};
    return keys;
}

const std::vector<std::string>& surface_shading_keys() {
    static const std::vector<std::string> keys = {"specular", "roughness", "bump_texture", "normal_texture", "bump_strength", "ao_texture"};
    return keys;
}

const std::vector<std::string>& light_keys() {
    static const std::vector<std::string> keys = {"type",         "color",      "intensity",   "position",   "direction",   "cone_angle",
                                                  "cone_falloff", "corner",     "edge_u",      "edge_v",     "texture",     "rotation",
                                                  "name",         "light_link", "shadow_link", "barn_doors", "cosine_power"};
    return keys;
}

namespace {

/// A light's texture (a sky, a quad's radiance, a spot's slide), every texel checked: a NaN,
/// infinite or absurd radiance is an error naming the pixel (it is read whole: any ray may
/// look anywhere in it).
std::shared_ptr<const LatLongMap> load_latlong(const std::string& path, const JsonReader& r, const std::string& key) {
    std::string unreadable;
    auto in = open_image(path, unreadable);
    if (!in) r.fail(key, "cannot read image \"" + path + "\": " + unreadable);
    const OIIO::ImageSpec& spec = in->spec();
    if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0)
        r.fail(key, fmt::format("image \"{}\" has an unusable size {}x{}", path, spec.width, spec.height));
    const double texels = static_cast<double>(spec.width) * spec.height;
    // The bound colour, displacement and fur maps refuse at (texture_problem): a light's map is
    // read whole and sampled by luminance, so no tiling lets a larger one through (a 20000^2 PNG
    // of 1.2 MB took minutes).
    if (texels > 8192.0 * 8192.0)
        r.fail(key, fmt::format("image \"{}\" is {}x{}: a light's texture is read whole and must hold at most 8192x8192 pixels; "
                                "resize it (e.g. OpenImageIO's oiiotool --resize)",
                                path, spec.width, spec.height));
    if (std::string why = memory_shortfall(texels * (spec.nchannels + 3) * sizeof(float), "reading " + path); !why.empty())
        r.fail(key, why);
    auto map = std::make_shared<LatLongMap>();
    map->width = spec.width;
    map->height = spec.height;
    std::vector<float> all(static_cast<size_t>(texels) * static_cast<size_t>(spec.nchannels));
    if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, all.data()))
        r.fail(key, "cannot read image \"" + path + "\": " + in->geterror());
    map->rgb.resize(static_cast<size_t>(texels) * 3);
    const auto nc = static_cast<size_t>(spec.nchannels);
    for (size_t i = 0; i < static_cast<size_t>(texels); ++i)
        for (size_t c = 0; c < 3; ++c) {
            const float v = all[i * nc + std::min(c, nc - 1)];
            if (!(v >= 0 && v <= kMaxRadiometric))
                r.fail(key, fmt::format("image \"{}\" pixel ({}, {}) holds {} (radiance must be finite, in [0, {:g}])", path,
                                        i % static_cast<size_t>(spec.width), i / static_cast<size_t>(spec.width), v, kMaxRadiometric));
            map->rgb[3 * i + c] = v;
        }
    return map;
}

/// A spot's "barn_doors": [left, right, top, bottom], degrees in [0, 90].
void read_barn_doors(const JsonReader& r, Light& l) {
    if (!r.has("barn_doors")) return;
    const json& b = r.raw("barn_doors");
    if (!b.is_array() || b.size() != 4) r.fail("barn_doors", "expected [left, right, top, bottom] in degrees");
    for (size_t i = 0; i < 4; ++i) l.barn_doors[i] = r.check_number(b[i], r.at("barn_doors") + fmt::format("/{}", i), 0, 90);
}

/// The light types, in the order users see them listed, and the keys each reads (beside type,
/// color, intensity, name and the links).
using LightTypeKeys = std::vector<std::pair<std::string, std::vector<std::string>>>;
const LightTypeKeys& light_types() {
    static const LightTypeKeys types = {
        {"point", {"position"}},
        {"spot", {"position", "direction", "cone_angle", "cone_falloff", "cosine_power", "texture", "barn_doors"}},
        {"distant", {"direction"}},
        {"quad", {"corner", "edge_u", "edge_v", "texture"}},
        {"sky", {"texture", "rotation"}}};
    return types;
}

const std::map<std::string, std::vector<std::string>>& keys_by_light_type() {
    static const std::map<std::string, std::vector<std::string>> keys(light_types().begin(), light_types().end());
    return keys;
}

std::vector<std::string> light_type_names() {
    std::vector<std::string> names;
    for (const auto& t : light_types()) names.push_back(t.first);
    return names;
}

}  // namespace

json light_defaults(const std::string& type) {
    const Light l;
    json d = json::object();
    if (!keys_by_light_type().count(type)) return d;
    d["color"] = to_json(l.color), d["intensity"] = kDefaultIntensity;
    if (type == "spot")
        d["direction"] = to_json(l.direction), d["cone_angle"] = l.cone_angle, d["cone_falloff"] = l.cone_falloff,
        d["cosine_power"] = l.cosine_power;
    if (type == "sky") d["rotation"] = l.sky_rotation;
    return d;
}

Transform read_transform(const JsonReader& obj) {
    if (!obj.has("transform")) return {};
    return read_transform_keys(
        JsonReader(obj.raw("transform"), obj.at("transform"), obj.ctx(), {"translate", "rotate", "scale", "matrix"}));
}

Transform read_transform_keys(const JsonReader& t) {
    if (t.has("matrix")) {
        if (t.has("translate") || t.has("rotate") || t.has("scale"))
            t.fail("matrix", "\"matrix\" cannot be combined with translate/rotate/scale");
        const json& m = t.raw("matrix");
        if (!m.is_array() || m.size() != 16) t.fail("matrix", "expected an array of 16 numbers (row-major)");
        Transform r;
        for (size_t i = 0; i < 16; ++i)
            r.m[i] = static_cast<float>(t.check_number(m[i], t.at("matrix") + "/" + std::to_string(i), -INFINITY, INFINITY));
        // As "scale": 0 is: a matrix that flattens space (all zeros, rank 2) has no normals to give.
        if (r.flattens()) t.fail("matrix", "the matrix is singular (it flattens the object)");
        return r;
    }
    Transform r;
    if (t.has("translate")) r = Transform::translate(t.vec3("translate", {}));
    if (t.has("rotate")) {
        const json& rot = t.raw("rotate");
        if (!rot.is_array() || rot.size() != 4) t.fail("rotate", "expected [degrees, axis_x, axis_y, axis_z]");
        float v[4];
        for (size_t i = 0; i < 4; ++i)
            v[i] = static_cast<float>(t.check_number(rot[i], t.at("rotate") + "/" + std::to_string(i), -INFINITY, INFINITY));
        Vec3 axis{v[1], v[2], v[3]};
        if (length(axis) == 0) t.fail("rotate", "rotation axis is zero");
        r = r * Transform::rotate(v[0], axis);
    }
    if (t.has("scale")) {
        const json& s = t.raw("scale");
        Vec3 sc = s.is_number() ? Vec3(static_cast<float>(t.check_number(s, t.at("scale"), -INFINITY, INFINITY))) : t.vec3("scale", {});
        if (sc.x == 0 || sc.y == 0 || sc.z == 0) t.fail("scale", "scale must not be zero");
        r = r * Transform::scale(sc);
    }
    return r;
}

namespace {

/// A texture key's file, checked as a texture (texture_problem).
std::string texture_file(const JsonReader& m, const std::string& key) {
    const std::string path = m.file(key, false);
    if (!path.empty())
        if (std::string why = texture_problem(path); !why.empty()) m.fail(key, "\"" + path + "\": " + why);
    return path;
}

/// Cutout opacity: `alpha_mode` (blend when only an opacity is given), `opacity`,
/// `opacity_texture` (read whole, opacity.h), `alpha_cutoff` (mask only).
void read_cutout(const JsonReader& m, Material& mat) {
    const bool given = m.has("opacity") || m.has("opacity_texture");
    const std::string mode = m.choice("alpha_mode", given ? "blend" : "opaque", {"opaque", "mask", "blend"});
    mat.alpha_mode = mode == "mask" ? AlphaMode::Mask : mode == "blend" ? AlphaMode::Blend : AlphaMode::Opaque;
    if (!mat.is_cutout() && given)
        m.fail("alpha_mode", "an opaque material reads no opacity: say \"mask\" or \"blend\", or remove the opacity keys");
    if (mat.alpha_mode != AlphaMode::Mask && m.has("alpha_cutoff"))
        m.fail("alpha_cutoff", "alpha_cutoff applies to alpha_mode \"mask\" only");
    mat.opacity = static_cast<float>(m.number("opacity", mat.opacity, 0, 1));
    mat.alpha_cutoff = static_cast<float>(m.number("alpha_cutoff", mat.alpha_cutoff, 0, 1));
    mat.opacity_texture = m.file("opacity_texture", false);
    if (!mat.opacity_texture.empty()) {
        std::string why;
        mat.opacity_map = load_opacity_map(mat.opacity_texture, OpacityChannel::AlphaOrFirst, why);
        if (!mat.opacity_map) m.fail("opacity_texture", "\"" + mat.opacity_texture + "\": " + why);
    }
}

/// "uv_transform": {"offset": [s, t], "rotation": radians, "scale": [s, t]}, KHR_texture_transform's.
UvTransform read_uv_transform(const JsonReader& m, const std::string& key) {
    if (!m.has(key)) return {};
    const JsonReader x(m.raw(key), m.at(key), m.ctx(), {"offset", "rotation", "scale"});
    const auto pair = [&](const char* k, Vec2 def) {
        if (!x.has(k)) return def;
        const json& v = x.raw(k);
        if (!v.is_array() || v.size() != 2) x.fail(k, "expected [s, t]");
        return Vec2{x.check_number(v[0], x.at(k) + "/0", -1e6, 1e6), x.check_number(v[1], x.at(k) + "/1", -1e6, 1e6)};
    };
    UvTransform t;
    std::string why;
    if (!make_uv_transform(pair("offset", t.offset), x.number("rotation", t.rotation, -1e6, 1e6), pair("scale", t.scale), t, why))
        x.fail("scale", why);
    return t;
}

/// glTF's metallic-roughness model, with its texture: `metallic` and `roughness` scale its blue
/// and green channels, and `specular` does not apply.
void read_metallic_roughness(const JsonReader& m, Material& mat) {
    mat.metallic_roughness_texture = texture_file(m, "metallic_roughness_texture");
    if (mat.metallic_roughness_texture.empty()) {
        if (m.has("metallic")) m.fail("metallic", "metallic applies with a metallic_roughness_texture only (say \"specular\" otherwise)");
        return;
    }
    if (m.has("specular")) m.fail("specular", "a metallic_roughness_texture gives the specular colour: leave \"specular\" out");
    mat.metallic = m.number("metallic", mat.metallic, 0, 1);
    mat.specular = Color(0.04f) * (1 - mat.metallic) + mat.color * mat.metallic;  // its mean, for what reads no texture
}

}  // namespace

Material read_material(const JsonReader& m, const std::string& name) {
    Material mat;
    mat.name = name;
    // Defaults are Material's own (scene.h), written once.
    mat.color = m.color("color", mat.color);
    for (int i = 0; i < 3; ++i)
        if (mat.color[i] > 1) m.fail("color", "albedo components must be <= 1 (energy conservation)");
    mat.color_texture = texture_file(m, "color_texture");
    // An emission texture alone emits as it is (emission defaults to 1 with one).
    mat.emission = m.color("emission", m.has("emission_texture") ? Color(1) : mat.emission);
    mat.specular = m.color("specular", mat.specular);
    for (int i = 0; i < 3; ++i)
        if (mat.specular[i] > 1) m.fail("specular", "specular components must be <= 1");
    mat.roughness = static_cast<float>(m.number("roughness", mat.roughness, 0.01, 1));
    mat.bump_texture = texture_file(m, "bump_texture");
    mat.ao_texture = texture_file(m, "ao_texture");
    mat.normal_texture = texture_file(m, "normal_texture");
    mat.bump_strength = static_cast<float>(m.number("bump_strength", mat.bump_strength, -1e3, 1e3));
    mat.mirror = m.color("mirror", mat.mirror);
    mat.transmission = m.color("transmission", mat.transmission);
    for (int i = 0; i < 3; ++i) {
        if (mat.mirror[i] > 1) m.fail("mirror", "mirror components must be <= 1 (energy conservation)");
        if (mat.transmission[i] > 1) m.fail("transmission", "transmission components must be <= 1 (energy conservation)");
    }
    // Real dielectrics lie in [1, 3] (diamond 2.42); below 1 would need the medium outside.
    mat.ior = static_cast<float>(m.number("ior", mat.ior, 1, 3));
    mat.absorption = m.color("absorption", mat.absorption);
    mat.diffuse_transmission = static_cast<float>(m.number("diffuse_transmission", mat.diffuse_transmission, 0, 1));
    mat.diffuse_transmission_color = m.color("diffuse_transmission_color", mat.diffuse_transmission_color);
    for (int i = 0; i < 3; ++i)
        if (mat.diffuse_transmission_color[i] > 1)
            m.fail("diffuse_transmission_color", "diffuse_transmission_color components must be <= 1 (energy conservation)");
    if (mat.is_translucent() && mat.is_dielectric())
        m.fail("diffuse_transmission", "a material is glass (transmission) or thin and translucent (diffuse_transmission), not both");
    read_cutout(m, mat);
    read_metallic_roughness(m, mat);
    mat.uv_transform = read_uv_transform(m, "uv_transform");
    mat.emission_texture = m.file("emission_texture", false);
    if (!mat.emission_texture.empty()) {
        std::string why;
        mat.emission_map = load_emission_map(mat.emission_texture, why);
        if (!mat.emission_map) m.fail("emission_texture", "\"" + mat.emission_texture + "\": " + why);
    }
    return mat;
}

Light read_light(const JsonReader& r) {
    std::string type = r.choice("type", "", light_type_names());
    std::vector<std::string> allowed = keys_by_light_type().at(type);
    for (const char* k : {"type", "color", "intensity", "name", "light_link", "shadow_link"}) allowed.emplace_back(k);
    r.only(allowed, "a " + type + " light");
    Light l;
    // Defaults are Light's own (scene.h), written once.
    l.color = r.color("color", l.color) * r.number("intensity", kDefaultIntensity, 0, kMaxRadiometric);
    for (int i = 0; i < 3; ++i)
        if (!(l.color[i] <= kMaxRadiometric)) r.fail("intensity", fmt::format("color x intensity exceeds {:g}", kMaxRadiometric));
    if (type == "point" || type == "spot") {
        l.type = type == "point" ? LightType::Point : LightType::Spot;
        l.position = r.vec3("position", {}, true);
        if (type == "spot") {
            l.direction = r.vec3("direction", l.direction);
            if (length(l.direction) == 0) r.fail("direction", "direction is zero");
            l.direction = normalize(l.direction);
            l.cone_angle = static_cast<float>(r.number("cone_angle", l.cone_angle, 0, 90));
            l.cone_falloff = static_cast<float>(r.number("cone_falloff", l.cone_falloff, 0, 90));
            l.cosine_power = static_cast<float>(r.number("cosine_power", l.cosine_power, 0, 1000));
            read_barn_doors(r, l);
            if (std::string tex = r.file("texture", false); !tex.empty()) l.texture = load_latlong(tex, r, "texture");
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
        if (std::string tex = r.file("texture", false); !tex.empty()) l.texture = load_latlong(tex, r, "texture");
    } else {
        l.type = LightType::Sky;
        l.sky_rotation = static_cast<float>(r.number("rotation", l.sky_rotation));
        std::string tex = r.file("texture", false);
        if (!tex.empty()) l.sky_map = load_latlong(tex, r, "texture");
    }
    return l;
}

}  // namespace bounce
