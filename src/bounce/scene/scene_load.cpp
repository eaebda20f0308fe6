#include "bounce/scene/scene_load.h"

#include <OpenImageIO/imageio.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <fmt/format.h>

#include <assimp/Importer.hpp>
#include <cstring>
#include <filesystem>
#include <optional>
#include <fstream>
#include <set>
#include <sstream>

#include "bounce/core/error.h"
#include "bounce/core/random.h"

namespace bounce {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// ---------------------------------------------------------------------------------------------
// Validating reader over the JSON DOM. Every error carries the JSON pointer of the value; values
// that came from the command line (--set, --res ...) are reported against "command line".

struct Context {
    std::string file;
    fs::path dir;
    std::set<std::string> cli_pointers;

    [[noreturn]] void fail(const std::string& ptr, const std::string& msg) const {
        for (const auto& p : cli_pointers)
            if (ptr == p || ptr.rfind(p + "/", 0) == 0)
                throw InputError("command line", "--set " + ptr, msg);
        throw InputError(file, ptr.empty() ? "/" : ptr, msg);
    }
};

const char* type_name(const json& j) {
    switch (j.type()) {
        case json::value_t::object: return "an object";
        case json::value_t::array: return "an array";
        case json::value_t::string: return "a string";
        case json::value_t::boolean: return "a boolean";
        case json::value_t::null: return "null";
        default: return "a number";
    }
}

class Reader {
public:
    Reader(const json& j, std::string ptr, const Context& ctx, std::vector<std::string> allowed)
        : j_(j), ptr_(std::move(ptr)), ctx_(ctx) {
        if (!j_.is_object()) ctx_.fail(ptr_, fmt::format("expected an object, got {}", type_name(j_)));
        for (auto it = j_.begin(); it != j_.end(); ++it) {
            if (std::find(allowed.begin(), allowed.end(), it.key()) != allowed.end()) continue;
            std::string hint = closest_match(it.key(), allowed);
            ctx_.fail(at(it.key()), fmt::format("unknown key \"{}\"{}", it.key(),
                                                hint.empty() ? fmt::format(" (valid keys: {})",
                                                                           fmt::join(allowed, ", "))
                                                             : " (did you mean \"" + hint + "\"?)"));
        }
    }

    std::string at(const std::string& key) const { return ptr_ + "/" + key; }
    bool has(const std::string& key) const { return j_.contains(key); }
    const json& raw(const std::string& key) const { return j_.at(key); }
    [[noreturn]] void fail(const std::string& key, const std::string& msg) const {
        ctx_.fail(key.empty() ? ptr_ : at(key), msg);
    }
    const Context& ctx() const { return ctx_; }
    const std::string& pointer() const { return ptr_; }

    double number(const std::string& key, double def, double lo = -INFINITY, double hi = INFINITY,
                  bool required = false) const {
        if (!has(key)) {
            if (required) fail("", fmt::format("missing required key \"{}\"", key));
            return def;
        }
        return check_number(raw(key), at(key), lo, hi);
    }
    int integer(const std::string& key, int def, int lo, int hi) const {
        if (!has(key)) return def;
        const json& v = raw(key);
        if (!v.is_number_integer())
            ctx_.fail(at(key), fmt::format("expected an integer, got {}", type_name(v)));
        auto x = v.get<int64_t>();
        if (x < lo || x > hi) ctx_.fail(at(key), fmt::format("{} is out of range [{}, {}]", x, lo, hi));
        return static_cast<int>(x);
    }
    Vec3 vec3(const std::string& key, Vec3 def, bool required = false) const {
        if (!has(key)) {
            if (required) fail("", fmt::format("missing required key \"{}\"", key));
            return def;
        }
        return to_vec3(raw(key), at(key));
    }
    /// A colour: [r,g,b] or one number for grey; components must be >= 0.
    Color color(const std::string& key, Color def) const {
        if (!has(key)) return def;
        const json& v = raw(key);
        if (v.is_number()) {
            auto g = static_cast<float>(check_number(v, at(key), 0, INFINITY));
            return Color(g);
        }
        Vec3 c = to_vec3(v, at(key));
        for (int i = 0; i < 3; ++i)
            if (c[i] < 0) ctx_.fail(at(key) + "/" + std::to_string(i), "colour components must be >= 0");
        return c;
    }
    std::string string(const std::string& key, const std::string& def, bool required = false) const {
        if (!has(key)) {
            if (required) fail("", fmt::format("missing required key \"{}\"", key));
            return def;
        }
        const json& v = raw(key);
        if (!v.is_string()) ctx_.fail(at(key), fmt::format("expected a string, got {}", type_name(v)));
        return v.get<std::string>();
    }
    bool boolean(const std::string& key, bool def) const {
        if (!has(key)) return def;
        const json& v = raw(key);
        if (!v.is_boolean()) ctx_.fail(at(key), fmt::format("expected true or false, got {}", type_name(v)));
        return v.get<bool>();
    }
    std::string choice(const std::string& key, const std::string& def,
                       const std::vector<std::string>& options) const {
        std::string s = string(key, def, def.empty());
        if (std::find(options.begin(), options.end(), s) == options.end())
            ctx_.fail(at(key), fmt::format("unknown value \"{}\" (valid: {})", s, fmt::join(options, ", ")));
        return s;
    }
    /// A file name, resolved against the scene's folder; must exist.
    std::string file(const std::string& key, bool required) const {
        std::string s = string(key, "", required);
        if (s.empty()) return s;
        fs::path p = fs::path(s).is_absolute() ? fs::path(s) : ctx_.dir / s;
        std::error_code ec;
        if (!fs::is_regular_file(p, ec))
            ctx_.fail(at(key), fmt::format("file not found: \"{}\"", p.string()));
        return p.lexically_normal().string();
    }

    double check_number(const json& v, const std::string& ptr, double lo, double hi) const {
        if (!v.is_number()) ctx_.fail(ptr, fmt::format("expected a number, got {}", type_name(v)));
        double x = v.get<double>();
        if (!std::isfinite(x)) ctx_.fail(ptr, "number is not finite");
        if (x < lo || x > hi) ctx_.fail(ptr, fmt::format("{} is out of range [{}, {}]", x, lo, hi));
        return x;
    }
    Vec3 to_vec3(const json& v, const std::string& ptr) const {
        if (!v.is_array() || v.size() != 3)
            ctx_.fail(ptr, fmt::format("expected an array of 3 numbers, got {}", type_name(v)));
        Vec3 r;
        for (int i = 0; i < 3; ++i)
            r[i] = static_cast<float>(check_number(v[static_cast<size_t>(i)], ptr + "/" + std::to_string(i),
                                                   -INFINITY, INFINITY));
        return r;
    }

private:
    const json& j_;
    std::string ptr_;
    const Context& ctx_;
};

// ---------------------------------------------------------------------------------------------

std::string read_text_file(const std::string& path) {
    std::error_code ec;
    if (!fs::exists(path, ec)) throw InputError(path, "", "file not found");
    if (fs::is_directory(path, ec)) throw InputError(path, "", "is a directory, not a file");
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(path, "", "cannot open file for reading");
    std::stringstream ss;
    ss << in.rdbuf();
    if (in.bad()) throw InputError(path, "", "error while reading file");
    return ss.str();
}

json parse_json_text(const std::string& text, const std::string& path) {
    try {
        return json::parse(text);
    } catch (const json::parse_error& e) {
        size_t line = 1, col = 1;
        for (size_t i = 0; i + 1 < e.byte && i < text.size(); ++i) {
            if (text[i] == '\n') ++line, col = 1;
            else ++col;
        }
        std::string msg = e.what();
        auto pos = msg.find(": ", msg.find("column"));
        if (pos != std::string::npos) msg = msg.substr(pos + 2);
        throw InputError(path, fmt::format("{}:{}", line, col), "malformed JSON: " + msg);
    } catch (const json::exception& e) {  // e.g. a number that overflows a double
        std::string msg = e.what();
        auto pos = msg.find("] ");
        throw InputError(path, "", "malformed JSON: " + (pos == std::string::npos ? msg : msg.substr(pos + 2)));
    }
}

/// Splits "a.b.0.c=value" and writes value into the DOM; returns the JSON pointer it set.
std::string apply_override(json& doc, const std::string& assignment) {
    auto eq = assignment.find('=');
    if (eq == std::string::npos || eq == 0)
        throw InputError("command line", "--set " + assignment, "expected key=value");
    std::string key = assignment.substr(0, eq), text = assignment.substr(eq + 1);
    std::string ptr;
    std::stringstream ks(key);
    for (std::string part; std::getline(ks, part, '.');) {
        if (part.empty()) throw InputError("command line", "--set " + assignment, "empty path component");
        ptr += "/" + part;
    }
    json value;
    try {
        value = json::parse(text);
    } catch (const json::parse_error&) {
        value = text;  // a bare word is a string
    } catch (const json::out_of_range&) {
        throw InputError("command line", "--set " + ptr, "number is not finite: " + text);
    }
    json* node = &doc;
    std::stringstream ps(key);
    std::vector<std::string> parts;
    for (std::string part; std::getline(ps, part, '.');) parts.push_back(part);
    for (size_t i = 0; i < parts.size(); ++i) {
        const std::string& part = parts[i];
        bool last = i + 1 == parts.size();
        if (node->is_array()) {
            size_t idx = 0;
            try {
                idx = std::stoul(part);
            } catch (...) {
                throw InputError("command line", "--set " + key, "\"" + part + "\" is not an array index");
            }
            if (idx >= node->size())
                throw InputError("command line", "--set " + key,
                                 fmt::format("index {} is out of range (array has {} items)", idx, node->size()));
            node = &(*node)[idx];
        } else {
            if (node->is_null()) *node = json::object();
            if (!node->is_object())
                throw InputError("command line", "--set " + key, "\"" + part + "\" is inside a value that is not an object");
            node = &(*node)[part];
        }
        if (last) *node = value;
    }
    return ptr;
}

std::shared_ptr<const LatLongMap> load_latlong(const std::string& path, const Reader& r,
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

Transform read_transform(const Reader& obj) {
    if (!obj.has("transform")) return {};
    Reader t(obj.raw("transform"), obj.at("transform"), obj.ctx(), {"translate", "rotate", "scale", "matrix"});
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

Vec3 to_vec3(const aiVector3D& v) { return {v.x, v.y, v.z}; }
Vec3 to_vec3(const aiColor3D& v) { return {v.r, v.g, v.b}; }

Transform to_transform(const aiMatrix4x4& a) {
    Transform t;
    const float* src = &a.a1;
    for (int i = 0; i < 16; ++i) t.m[static_cast<size_t>(i)] = src[i];
    return t;
}

aiMatrix4x4 node_world(const aiNode* n) {
    aiMatrix4x4 m;
    for (; n; n = n->mParent) m = n->mTransformation * m;
    return m;
}

const unsigned kAssimpFlags = aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                              aiProcess_SortByPType | aiProcess_ValidateDataStructure;

const aiScene* import_file(Assimp::Importer& imp, const std::string& path) {
    imp.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
    const aiScene* s = imp.ReadFile(path, kAssimpFlags);
    if (!s) throw InputError(path, "", std::string("cannot load mesh: ") + imp.GetErrorString());
    return s;
}

struct GltfCamera {
    float yfov = 0, aspect = 0;
};

/// The first perspective camera of a .gltf/.glb file, read from its JSON.
std::optional<GltfCamera> gltf_camera(const std::string& path) {
    std::string ext = fs::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
    if (ext != ".gltf" && ext != ".glb") return std::nullopt;
    std::ifstream in(path, std::ios::binary);
    std::string text((std::istreambuf_iterator<char>(in)), {});
    if (ext == ".glb") {  // 12-byte header, then the JSON chunk: length, type, data
        if (text.size() < 20) return std::nullopt;
        uint32_t len = 0;
        std::memcpy(&len, text.data() + 12, 4);
        if (20 + static_cast<size_t>(len) > text.size()) return std::nullopt;
        text = text.substr(20, len);
    }
    json j = json::parse(text, nullptr, false);
    if (j.is_discarded() || !j.contains("cameras") || !j["cameras"].is_array() || j["cameras"].empty())
        return std::nullopt;
    const json& c = j["cameras"][0];
    if (!c.contains("perspective") || !c["perspective"].contains("yfov")) return std::nullopt;
    const json& p = c["perspective"];
    GltfCamera g;
    g.yfov = p["yfov"].is_number() ? p["yfov"].get<float>() : 0;
    g.aspect = p.contains("aspectRatio") && p["aspectRatio"].is_number() ? p["aspectRatio"].get<float>() : 0;
    if (!(g.yfov > 0)) return std::nullopt;
    return g;
}

/// Describes a bare mesh file as a JSON scene: the file's camera and punctual lights.
json describe_mesh_file(const std::string& path) {
    Assimp::Importer imp;
    const aiScene* s = import_file(imp, path);
    json doc;
    doc["objects"] = json::array({{{"name", fs::path(path).stem().string()}, {"file", fs::path(path).filename().string()}}});
    if (s->mNumCameras == 0)
        throw InputError(path, "", "the file has no camera; write a JSON scene that names one (docs/scene-format.md)");
    const aiCamera* cam = s->mCameras[0];
    const aiNode* node = s->mRootNode->FindNode(cam->mName);
    Transform w = node ? to_transform(node_world(node)) : Transform{};
    float aspect = cam->mAspect > 0 ? cam->mAspect : 1.0f;
    Vec3 pos, look, up;
    float vfov;
    if (auto gltf = gltf_camera(path)) {
        // glTF: the camera looks down -Z of its node with +Y up. Assimp 5.2 also copies the
        // node translation into mPosition and stores yfov*aspect as the "horizontal" fov, so
        // take the pose from the node and the field of view from the file itself.
        pos = w.point(Vec3(0));
        look = w.vector({0, 0, -1});
        up = w.vector({0, 1, 0});
        vfov = gltf->yfov * 180.0f / kPi;
        if (gltf->aspect > 0) aspect = gltf->aspect;
    } else {
        pos = w.point(to_vec3(cam->mPosition));
        look = w.vector(to_vec3(cam->mLookAt));
        up = w.vector(to_vec3(cam->mUp));
        // Assimp documents mHorizontalFOV as half the horizontal angle.
        vfov = 2.0f * std::atan(std::tan(cam->mHorizontalFOV) / aspect) * 180.0f / kPi;
    }
    int width = 640, height = std::max(1, static_cast<int>(std::lround(640.0f / aspect)));
    doc["camera"] = {{"position", {pos.x, pos.y, pos.z}},
                     {"look_at", {pos.x + look.x, pos.y + look.y, pos.z + look.z}},
                     {"up", {up.x, up.y, up.z}},
                     {"fov", vfov},
                     {"resolution", {width, height}}};
    json lights = json::array();
    for (unsigned i = 0; i < s->mNumLights; ++i) {
        const aiLight* l = s->mLights[i];
        const aiNode* ln = s->mRootNode->FindNode(l->mName);
        Transform lw = ln ? to_transform(node_world(ln)) : Transform{};
        Vec3 p = lw.point(to_vec3(l->mPosition));
        Vec3 d = normalize(lw.vector(to_vec3(l->mDirection)));
        Vec3 c = to_vec3(l->mColorDiffuse);  // glTF: colour x intensity
        json jl = {{"color", {c.x, c.y, c.z}}};
        switch (l->mType) {
            case aiLightSource_POINT:
                jl["type"] = "point";
                jl["position"] = {p.x, p.y, p.z};
                break;
            case aiLightSource_SPOT: {
                jl["type"] = "spot";
                jl["position"] = {p.x, p.y, p.z};
                jl["direction"] = {d.x, d.y, d.z};
                float inner = l->mAngleInnerCone * 180.0f / kPi, outer = l->mAngleOuterCone * 180.0f / kPi;
                jl["cone_angle"] = std::min(inner, outer);
                jl["cone_falloff"] = std::max(0.0f, outer - inner);
                break;
            }
            case aiLightSource_DIRECTIONAL:
                jl["type"] = "distant";
                jl["direction"] = {d.x, d.y, d.z};
                break;
            default: continue;  // area/ambient lights of other formats are not punctual
        }
        lights.push_back(jl);
    }
    if (lights.empty()) lights.push_back({{"type", "sky"}, {"color", 1.0}});
    doc["lights"] = lights;
    return doc;
}

Material read_material(const Reader& m, const std::string& name) {
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
    mat.normal_texture = m.file("normal_texture", false);
    mat.bump_strength = static_cast<float>(m.number("bump_strength", mat.bump_strength, -1e3, 1e3));
    return mat;
}

Light read_light(const Reader& r, const Scene& scene) {
    std::string type = r.choice("type", "", {"point", "spot", "distant", "quad", "sky"});
    Light l;
    l.color = r.color("color", Color(1)) * static_cast<float>(r.number("intensity", 1, 0));
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

void read_object(const Reader& r, Scene& scene, size_t index) {
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
    if (type == "mesh") {
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
        auto radius = static_cast<float>(r.number("radius", 1, 0, INFINITY));
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
        if (!isfinite(p)) r.fail("", "mesh has non-finite vertex positions");
    scene.objects.push_back(std::move(obj));
}

Scene build_scene(json doc, const std::string& path, const std::vector<std::string>& overrides) {
    Context ctx;
    ctx.file = path;
    ctx.dir = fs::path(path).parent_path();
    for (const auto& o : overrides) ctx.cli_pointers.insert(apply_override(doc, o));

    Scene scene;
    scene.path = path;
    scene.description = doc;
    Reader root(doc, "", ctx, {"camera", "render", "materials", "lights", "objects", "description"});

    // Render settings.
    if (root.has("render")) {
        Reader r(root.raw("render"), "/render", ctx,
                 {"spp", "seed", "threads", "light_samples", "ray_offset", "tile_size", "crop", "gi", "ao",
                  "rays", "ao_distance", "ao_falloff", "hit_light_samples", "concave_angle", "radiosity",
                  "radiosity_textures", "radiosity_texel", "radiosity_light_samples", "metric", "min_spacing",
                  "max_spacing", "max_angle", "gradient_limit", "quality", "min_weight", "accuracy", "gradients",
                  "neighbour_clamp", "preview", "shading_reach", "radius_scale", "tile_order", "cache_sharing", "light_per_channel"});
        RenderSettings& s = scene.render;
        s.spp = r.integer("spp", s.spp, 1, 4096);
        if (r.has("seed")) {
            const json& v = r.raw("seed");
            if (!v.is_number_unsigned() && !(v.is_number_integer() && v.get<int64_t>() >= 0))
                r.fail("seed", "expected a non-negative integer");
            s.seed = v.get<uint64_t>();
        }
        s.threads = r.integer("threads", s.threads, 0, 4096);
        s.light_samples = r.integer("light_samples", s.light_samples, 1, 65536);
        s.ray_offset = static_cast<float>(r.number("ray_offset", -1, 0));
        s.tile_size = r.integer("tile_size", s.tile_size, 1, 4096);
        s.tile_order = r.choice("tile_order", s.tile_order, {"rows", "spiral"});
        s.cache_sharing = r.choice("cache_sharing", s.cache_sharing, {"shared", "per-thread"});
        s.light_per_channel = r.boolean("light_per_channel", s.light_per_channel);
        s.gi = r.choice("gi", s.gi, {"none", "brute", "cache"});
        s.ao = r.boolean("ao", s.ao);
        s.rays = r.integer("rays", s.rays, 1, 1 << 20);
        s.ao_distance = static_cast<float>(r.number("ao_distance", s.ao_distance, 0));
        s.ao_falloff = static_cast<float>(r.number("ao_falloff", s.ao_falloff, 0, 100));
        s.hit_light_samples = r.integer("hit_light_samples", s.hit_light_samples, 1, 65536);
        s.concave_angle = static_cast<float>(r.number("concave_angle", s.concave_angle, 0, 90));
        s.radiosity = r.boolean("radiosity", s.radiosity);
        s.radiosity_textures = r.string("radiosity_textures", s.radiosity_textures);
        if (!s.radiosity_textures.empty() && fs::path(s.radiosity_textures).is_relative() &&
            !ctx.cli_pointers.count("/render/radiosity_textures"))
            s.radiosity_textures = (ctx.dir / s.radiosity_textures).string();
        s.radiosity_texel = static_cast<float>(r.number("radiosity_texel", s.radiosity_texel, 0));
        s.radiosity_light_samples = r.integer("radiosity_light_samples", s.radiosity_light_samples, 1, 65536);
        s.metric = r.choice("metric", s.metric, {"tl04", "ward"});
        s.min_spacing = static_cast<float>(r.number("min_spacing", s.min_spacing, 0.1, 4096));
        s.max_spacing = static_cast<float>(r.number("max_spacing", s.max_spacing, 0.1, 4096));
        if (s.max_spacing < s.min_spacing) r.fail("max_spacing", "max_spacing is below min_spacing");
        s.max_angle = static_cast<float>(r.number("max_angle", s.max_angle, 0.1, 90));
        s.gradient_limit = static_cast<float>(r.number("gradient_limit", s.gradient_limit, 0, 1e6));
        s.quality = static_cast<float>(r.number("quality", s.quality, 0.01, 100));
        s.min_weight = static_cast<float>(r.number("min_weight", s.min_weight, 1e-6, 100));
        s.accuracy = static_cast<float>(r.number("accuracy", s.accuracy, 1e-3, 10));
        s.gradients = r.boolean("gradients", s.gradients);
        s.neighbour_clamp = r.boolean("neighbour_clamp", s.neighbour_clamp);
        s.preview = r.boolean("preview", s.preview);
        s.shading_reach = static_cast<float>(r.number("shading_reach", s.shading_reach, 1, 10));
        s.radius_scale = static_cast<float>(r.number("radius_scale", s.radius_scale, 0.01, 100));
        if (r.has("crop")) {
            const json& c = r.raw("crop");
            if (!c.is_array() || c.size() != 4) r.fail("crop", "expected [x0, x1, y0, y1]");
            for (size_t i = 0; i < 4; ++i) {
                if (!c[i].is_number_integer() || c[i].get<int64_t>() < 0)
                    ctx.fail("/render/crop/" + std::to_string(i), "expected a non-negative integer");
                s.crop[i] = static_cast<int>(c[i].get<int64_t>());
            }
        }
    }

    // Camera.
    if (!root.has("camera")) root.fail("", "missing required key \"camera\"");
    {
        Reader c(root.raw("camera"), "/camera", ctx, {"position", "look_at", "up", "fov", "resolution"});
        Camera& cam = scene.camera;
        cam.position = c.vec3("position", {}, true);
        cam.look_at = c.vec3("look_at", {}, true);
        cam.up = c.vec3("up", {0, 1, 0});
        cam.fov = static_cast<float>(c.number("fov", 45, 0, 180));
        if (cam.fov <= 0 || cam.fov >= 180) c.fail("fov", "fov must be in (0, 180) degrees");
        if (length(cam.look_at - cam.position) == 0) c.fail("look_at", "look_at equals position");
        if (length(cross(cam.look_at - cam.position, cam.up)) == 0) c.fail("up", "up is parallel to the view direction");
        if (c.has("resolution")) {
            const json& res = c.raw("resolution");
            if (!res.is_array() || res.size() != 2) c.fail("resolution", "expected [width, height]");
            for (size_t i = 0; i < 2; ++i) {
                const json& v = res[i];
                std::string p = "/camera/resolution/" + std::to_string(i);
                if (!v.is_number_integer()) ctx.fail(p, fmt::format("expected an integer, got {}", type_name(v)));
                int64_t x = v.get<int64_t>();
                if (x < 1 || x > 65536) ctx.fail(p, fmt::format("resolution {} is out of range [1, 65536]", x));
                (i == 0 ? cam.width : cam.height) = static_cast<int>(x);
            }
        }
    }
    const auto& crop = scene.render.crop;
    if (scene.render.has_crop() &&
        (crop[0] >= crop[1] || crop[2] >= crop[3] || crop[1] > scene.camera.width || crop[3] > scene.camera.height))
        ctx.fail("/render/crop", fmt::format("crop [{}, {}, {}, {}] is empty or outside the {}x{} image",
                                            crop[0], crop[1], crop[2], crop[3], scene.camera.width, scene.camera.height));

    // Materials.
    if (root.has("materials")) {
        const json& mats = root.raw("materials");
        if (!mats.is_object()) root.fail("materials", "expected an object of named materials");
        for (auto it = mats.begin(); it != mats.end(); ++it) {
            Reader m(it.value(), "/materials/" + it.key(), ctx, {"color", "color_texture", "emission", "specular", "roughness", "bump_texture",
                                                                  "normal_texture", "bump_strength"});
            scene.materials.push_back(read_material(m, it.key()));
        }
    }

    // Objects.
    if (!root.has("objects")) root.fail("", "missing required key \"objects\"");
    const json& objs = root.raw("objects");
    if (!objs.is_array() || objs.empty()) root.fail("objects", "expected a non-empty array of objects");
    for (size_t i = 0; i < objs.size(); ++i) {
        Reader o(objs[i], fmt::format("/objects/{}", i), ctx,
                 {"name", "type", "file", "material", "transform", "fine_subdivisions", "vertices",
                  "center", "radius", "subdivisions"});
        read_object(o, scene, i);
    }

    // Lights: explicit ones, then one mesh light per object with emissive faces.
    if (root.has("lights")) {
        const json& ls = root.raw("lights");
        if (!ls.is_array()) root.fail("lights", "expected an array of lights");
        for (size_t i = 0; i < ls.size(); ++i) {
            Reader l(ls[i], fmt::format("/lights/{}", i), ctx,
                     {"type", "color", "intensity", "position", "direction", "cone_angle",
                      "cone_falloff", "corner", "edge_u", "edge_v", "texture", "rotation", "name"});
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

TriangleMesh load_mesh_file(const std::string& path, const std::string& prefix,
                            std::vector<Material>& materials, int override_material) {
    Assimp::Importer imp;
    const aiScene* s = import_file(imp, path);
    std::vector<uint32_t> mat_map(s->mNumMaterials);
    if (override_material < 0) {
        for (unsigned i = 0; i < s->mNumMaterials; ++i) {
            const aiMaterial* am = s->mMaterials[i];
            Material m;
            aiString name;
            am->Get(AI_MATKEY_NAME, name);
            m.name = prefix + "/" + (name.length ? name.C_Str() : std::to_string(i));
            aiColor4D base;
            aiColor3D diffuse;
            if (am->Get(AI_MATKEY_BASE_COLOR, base) == AI_SUCCESS) m.color = {base.r, base.g, base.b};
            else if (am->Get(AI_MATKEY_COLOR_DIFFUSE, diffuse) == AI_SUCCESS) m.color = to_vec3(diffuse);
            m.color = vmin(vmax(m.color, Color(0)), Color(1));
            aiColor3D ke;
            if (am->Get(AI_MATKEY_COLOR_EMISSIVE, ke) == AI_SUCCESS) m.emission = vmax(to_vec3(ke), Color(0));
            // Glossy lobe: glTF metallic-roughness (F0 = mix(0.04, base, metallic), the diffuse
            // part darkened by 1 - metallic), or MTL's Ks and Ns (Blinn-Phong exponent to GGX
            // roughness: alpha = sqrt(2 / (Ns + 2))).
            float metallic = 0, rough = 1, ns = 0;
            aiColor3D ks;
            if (am->Get(AI_MATKEY_ROUGHNESS_FACTOR, rough) == AI_SUCCESS) {
                am->Get(AI_MATKEY_METALLIC_FACTOR, metallic);
                metallic = std::clamp(metallic, 0.0f, 1.0f);
                m.specular = Color(0.04f) * (1 - metallic) + m.color * metallic;
                m.color = m.color * (1 - metallic);
                m.roughness = std::clamp(rough, 0.01f, 1.0f);
            } else if (am->Get(AI_MATKEY_COLOR_SPECULAR, ks) == AI_SUCCESS && (ks.r > 0 || ks.g > 0 || ks.b > 0)) {
                m.specular = vmin(vmax(to_vec3(ks), Color(0)), Color(1));
                if (am->Get(AI_MATKEY_SHININESS, ns) == AI_SUCCESS && ns > 0)
                    m.roughness = std::clamp(std::sqrt(std::sqrt(2 / (ns + 2))), 0.01f, 1.0f);
            }
            auto texture = [&](std::initializer_list<aiTextureType> types) -> std::string {
                aiString tex;
                for (aiTextureType type : types) {
                    if (am->GetTexture(type, 0, &tex) != AI_SUCCESS || tex.C_Str()[0] == '*') continue;
                    fs::path t = fs::path(path).parent_path() / tex.C_Str();
                    std::error_code ec;
                    if (fs::is_regular_file(t, ec)) return t.lexically_normal().string();
                }
                return "";
            };
            m.color_texture = texture({aiTextureType_BASE_COLOR, aiTextureType_DIFFUSE});
            if (!m.color_texture.empty()) m.color = Color(1 - metallic);
            // Assimp files MTL's bump maps under HEIGHT, glTF's normalTexture under NORMALS.
            m.bump_texture = texture({aiTextureType_HEIGHT, aiTextureType_DISPLACEMENT});
            m.normal_texture = texture({aiTextureType_NORMALS});
            mat_map[i] = static_cast<uint32_t>(materials.size());
            materials.push_back(m);
        }
    }
    TriangleMesh out;
    // Walk the node tree so each mesh instance gets its node's transform.
    std::vector<std::pair<const aiNode*, aiMatrix4x4>> stack{{s->mRootNode, s->mRootNode->mTransformation}};
    while (!stack.empty()) {
        auto [node, world] = stack.back();
        stack.pop_back();
        for (unsigned c = 0; c < node->mNumChildren; ++c)
            stack.emplace_back(node->mChildren[c], world * node->mChildren[c]->mTransformation);
        Transform t = to_transform(world);
        for (unsigned k = 0; k < node->mNumMeshes; ++k) {
            const aiMesh* am = s->mMeshes[node->mMeshes[k]];
            if (!(am->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
            TriangleMesh m;
            for (unsigned v = 0; v < am->mNumVertices; ++v) {
                m.positions.push_back(t.point(to_vec3(am->mVertices[v])));
                if (am->mNormals) m.normals.push_back(t.normal(to_vec3(am->mNormals[v])));
                if (am->mTextureCoords[0])
                    m.uvs.push_back({am->mTextureCoords[0][v].x, am->mTextureCoords[0][v].y});
            }
            uint32_t mat = override_material >= 0 ? static_cast<uint32_t>(override_material)
                                                  : mat_map[am->mMaterialIndex];
            for (unsigned f = 0; f < am->mNumFaces; ++f) {
                const aiFace& face = am->mFaces[f];
                if (face.mNumIndices != 3) continue;
                m.indices.insert(m.indices.end(), {face.mIndices[0], face.mIndices[1], face.mIndices[2]});
                m.face_materials.push_back(mat);
            }
            out.append(m);
        }
    }
    if (out.triangle_count() == 0) throw InputError(path, "", "mesh has no triangles");
    return out;
}

Scene load_scene_text(const std::string& text, const std::string& path,
                      const std::vector<std::string>& overrides) {
    return build_scene(parse_json_text(text, path), path, overrides);
}

Scene load_scene(const std::string& path, const std::vector<std::string>& overrides) {
    std::string ext = fs::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
    if (ext == ".json") return load_scene_text(read_text_file(path), path, overrides);
    {
        std::error_code ec;
        if (!fs::is_regular_file(path, ec)) throw InputError(path, "", "file not found");
    }
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
                    for (const char* key : {"specular", "roughness", "bump_texture", "normal_texture", "bump_strength"})
                        m.erase(key);
        std::string s = part + "=" + (value.is_null() ? "" : value.dump());
        for (unsigned char c : s) h = hash_combine(h, c);
    }
    return h;
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
