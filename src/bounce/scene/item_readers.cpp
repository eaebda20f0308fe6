#include "bounce/scene/item_readers.h"

#include <OpenImageIO/imageio.h>
#include <fmt/format.h>

#include <cmath>
#include <map>

#include "bounce/core/error.h"
#include "bounce/core/image.h"
#include "bounce/core/memory.h"

namespace bounce {

using nlohmann::json;

const std::vector<std::string>& material_keys() {
    static const std::vector<std::string> keys = {"color",          "color_texture", "emission",      "specular",  "roughness",
                                                  "bump_texture",   "normal_texture", "bump_strength", "ao_texture"};
    return keys;
}

const std::vector<std::string>& light_keys() {
    static const std::vector<std::string> keys = {"type",   "color",  "intensity", "position", "direction", "cone_angle", "cone_falloff",
                                                  "corner", "edge_u", "edge_v",    "texture",  "rotation",  "name"};
    return keys;
}

namespace {

/// A sky texture, every texel checked: a NaN, infinite or absurd radiance is an error naming
/// the pixel (a sky is read whole: every gather ray may look anywhere in it).
std::shared_ptr<const LatLongMap> load_latlong(const std::string& path, const JsonReader& r,
                                               const std::string& key) {
    auto in = OIIO::ImageInput::open(path);
    if (!in) r.fail(key, "cannot read image \"" + path + "\": " + OIIO::geterror());
    const OIIO::ImageSpec& spec = in->spec();
    if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0)
        r.fail(key, fmt::format("image \"{}\" has an unusable size {}x{}", path, spec.width, spec.height));
    const double texels = static_cast<double>(spec.width) * spec.height;
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
                                        i % static_cast<size_t>(spec.width), i / static_cast<size_t>(spec.width), v,
                                        kMaxRadiometric));
            map->rgb[3 * i + c] = v;
        }
    return map;
}

/// The keys each light type reads (beside type, color, intensity and name).
const std::map<std::string, std::vector<std::string>>& keys_by_light_type() {
    static const std::map<std::string, std::vector<std::string>> keys = {
        {"point", {"position"}},
        {"spot", {"position", "direction", "cone_angle", "cone_falloff"}},
        {"distant", {"direction"}},
        {"quad", {"corner", "edge_u", "edge_v"}},
        {"sky", {"texture", "rotation"}}};
    return keys;
}

}  // namespace

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


namespace {

/// A texture key's file, checked as a texture (texture_problem).
std::string texture_file(const JsonReader& m, const std::string& key) {
    const std::string path = m.file(key, false);
    if (!path.empty())
        if (std::string why = texture_problem(path); !why.empty()) m.fail(key, "\"" + path + "\": " + why);
    return path;
}

}  // namespace

Material read_material(const JsonReader& m, const std::string& name) {
    Material mat;
    mat.name = name;
    mat.color = m.color("color", Color(0.7f));
    for (int i = 0; i < 3; ++i)
        if (mat.color[i] > 1) m.fail("color", "albedo components must be <= 1 (energy conservation)");
    mat.color_texture = texture_file(m, "color_texture");
    mat.emission = m.color("emission", Color(0));
    mat.specular = m.color("specular", Color(0));
    for (int i = 0; i < 3; ++i)
        if (mat.specular[i] > 1) m.fail("specular", "specular components must be <= 1");
    mat.roughness = static_cast<float>(m.number("roughness", mat.roughness, 0.01, 1));
    mat.bump_texture = texture_file(m, "bump_texture");
    mat.ao_texture = texture_file(m, "ao_texture");
    mat.normal_texture = texture_file(m, "normal_texture");
    mat.bump_strength = static_cast<float>(m.number("bump_strength", mat.bump_strength, -1e3, 1e3));
    return mat;
}

Light read_light(const JsonReader& r) {
    std::string type = r.choice("type", "", {"point", "spot", "distant", "quad", "sky"});
    std::vector<std::string> allowed = keys_by_light_type().at(type);
    for (const char* k : {"type", "color", "intensity", "name"}) allowed.emplace_back(k);
    r.only(allowed, "a " + type + " light");
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
    return l;
}


}  // namespace bounce
