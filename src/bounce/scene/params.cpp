#include "bounce/scene/params.h"

#include <fmt/format.h>

#include <cfloat>
#include <cmath>
#include <type_traits>

#include "bounce/scene/json_reader.h"

namespace bounce {

using nlohmann::json;

namespace {

/// A row bound to one field of one stage's settings struct. The type follows the field's.
template <class Group, class T>
Param field(const char* key, const char* stage, Group RenderSettings::*group, T Group::*member) {
    Param p;
    p.key = std::string("render.") + key;
    p.stage = stage;
    if constexpr (std::is_same_v<T, int>) p.type = ParamType::Int;
    else if constexpr (std::is_same_v<T, uint64_t>) p.type = ParamType::UInt64;
    else if constexpr (std::is_same_v<T, float>) p.type = ParamType::Float;
    else if constexpr (std::is_same_v<T, bool>) p.type = ParamType::Bool;
    else if constexpr (std::is_same_v<T, std::string>) p.type = ParamType::Path;
    else if constexpr (std::is_enum_v<T>) p.type = ParamType::Enum;
    else {
        p.type = ParamType::IntList;
        p.count = std::tuple_size_v<T>;
    }
    p.get = [group, member](const Scene& s) -> json {
        const T& v = s.render.*group.*member;
        if constexpr (std::is_enum_v<T>) return static_cast<int>(v);  // named by Row::choices
        else return v;
    };
    p.set = [group, member](Scene& s, const json& v) {
        T& dst = s.render.*group.*member;
        if constexpr (std::is_enum_v<T>) dst = static_cast<T>(v.get<int>());
        else dst = v.get<T>();
    };
    return p;
}

/// Chained setters keep each row of the table on a few readable lines.
struct Row {
    Param p;
    Row& range(double lo, double hi) { p.lo = lo, p.hi = hi; return *this; }
    Row& unit(const char* u) { p.unit = u; return *this; }
    Row& doc(const char* d) { p.doc = d; return *this; }
    Row& id(unsigned mask) { p.identity = mask; return *this; }
    Row& animate() { p.animatable = true; return *this; }
    /// The CLI flag: "--" and the key's name with dashes, unless given.
    Row& flag(std::string f = "") {
        if (f.empty()) {
            f = "--" + p.name();
            for (char& c : f) c = c == '_' ? '-' : c;
        }
        p.flag = f;
        return *this;
    }
    Row& automatic(float sentinel) {  // a float whose sentinel value reads "auto"
        p.type = ParamType::FloatAuto;
        auto get = p.get;
        auto set = p.set;
        p.get = [get, sentinel](const Scene& s) -> json {
            json v = get(s);
            return v.get<float>() == sentinel ? json("auto") : v;
        };
        p.set = [set, sentinel](Scene& s, const json& v) { set(s, v.is_string() ? json(sentinel) : v); };
        return *this;
    }
    Row& choices(std::vector<std::string> names) {
        p.choices = names;
        auto get = p.get;
        auto set = p.set;
        p.get = [get, names](const Scene& s) -> json { return names.at(get(s).get<size_t>()); };
        p.set = [set, names](Scene& s, const json& v) {
            auto it = std::find(names.begin(), names.end(), v.get<std::string>());
            set(s, static_cast<int>(it - names.begin()));
        };
        return *this;
    }
};

template <class Group, class T>
Row row(const char* key, const char* stage, Group RenderSettings::*group, T Group::*member) {
    return Row{field(key, stage, group, member)};
}

Row camera_vec3(const char* key, Vec3 Camera::*member, const char* doc, bool required) {
    Param p;
    p.key = std::string("camera.") + key;
    p.stage = "camera";
    p.type = ParamType::Vec3;
    p.lo = -kMaxCoordinate, p.hi = kMaxCoordinate;
    p.unit = "world";
    p.doc = doc;
    p.required = required;
    p.identity = kDeepIdentity;  // caches check the camera's fingerprint
    p.get = [member](const Scene& s) -> json {
        const Vec3& v = s.camera.*member;
        return json::array({v.x, v.y, v.z});
    };
    p.set = [member](Scene& s, const json& v) {
        s.camera.*member = {v[0].get<float>(), v[1].get<float>(), v[2].get<float>()};
    };
    return Row{p};
}

ParamTable make_table() {
    using R = RenderSettings;
    const unsigned deep = kDeepIdentity, rad = kRadiosityIdentity, cache = kCacheIdentity;
    std::vector<Row> rows;
    // Camera.
    rows.push_back(camera_vec3("position", &Camera::position, "where the camera is", true).animate());
    rows.push_back(camera_vec3("look_at", &Camera::look_at, "the point it looks at", true).animate());
    rows.push_back(camera_vec3("up", &Camera::up, "up direction; must not be parallel to the view", false).animate());
    {
        Row r;
        r.p.key = "camera.fov";
        r.p.stage = "camera";
        r.p.type = ParamType::Float;
        r.p.get = [](const Scene& s) -> json { return s.camera.fov; };
        r.p.set = [](Scene& s, const json& v) { s.camera.fov = v.get<float>(); };
        rows.push_back(r.range(0.001, 179.999).unit("degrees").doc("vertical field of view").id(deep).animate());
    }
    {
        Row r;
        r.p.key = "camera.shutter";
        r.p.stage = "camera";
        r.p.type = ParamType::FloatList;
        r.p.count = 2;
        r.p.get = [](const Scene& s) -> json { return json::array({s.camera.shutter[0], s.camera.shutter[1]}); };
        r.p.set = [](Scene& s, const json& v) { s.camera.shutter = {v[0].get<float>(), v[1].get<float>()}; };
        rows.push_back(r.range(-1, 1).unit("frames")
                           .doc("[open, close] around the frame's time: primary visibility is blurred over it (keyed objects, "
                                "meshes playing a clip and a keyed camera move in it), shading is at the frame's time; "
                                "[0, 0] = no motion blur")
                           .id(deep).animate());
    }
    {
        Row r;
        r.p.key = "camera.aperture";
        r.p.stage = "camera";
        r.p.type = ParamType::Float;
        r.p.get = [](const Scene& s) -> json { return s.camera.aperture; };
        r.p.set = [](Scene& s, const json& v) { s.camera.aperture = v.get<float>(); };
        rows.push_back(r.range(0, kMaxCoordinate).unit("world")
                           .doc("lens diameter (thin lens): depth of field; 0 = pinhole").id(deep).animate());
    }
    {
        Row r;
        r.p.key = "camera.focus_distance";
        r.p.stage = "camera";
        r.p.type = ParamType::Float;
        r.p.get = [](const Scene& s) -> json { return s.camera.focus_distance; };
        r.p.set = [](Scene& s, const json& v) { s.camera.focus_distance = v.get<float>(); };
        rows.push_back(r.automatic(0).range(0, kMaxCoordinate).unit("world")
                           .doc("distance of the plane in focus along the view; auto = the distance to look_at").id(deep).animate());
    }
    {
        Row r;
        r.p.key = "camera.resolution";
        r.p.stage = "camera";
        r.p.type = ParamType::IntList;
        r.p.count = 2;
        r.p.get = [](const Scene& s) -> json { return json::array({s.camera.width, s.camera.height}); };
        r.p.set = [](Scene& s, const json& v) { s.camera.width = v[0].get<int>(), s.camera.height = v[1].get<int>(); };
        rows.push_back(r.range(1, 65536).unit("pixels").doc("[width, height]; on the CLI WIDTHxHEIGHT").id(deep).flag("--res"));
    }
    // Primary visibility and the deep file.
    rows.push_back(row("spp", "visibility", &R::visibility, &VisibilitySettings::spp).range(1, 4096).unit("samples")
                       .doc("jittered subsamples per pixel (primary visibility)").id(deep).flag());
    rows.push_back(row("seed", "visibility", &R::visibility, &VisibilitySettings::seed).range(0, 1.8446744073709552e19)
                       .doc("random seed; every random number is a hash of (pixel, sample, dimension, seed)").id(deep | cache).flag());
    rows.push_back(row("crop", "visibility", &R::visibility, &VisibilitySettings::crop).range(0, 65536).unit("pixels")
                       .doc("[x0, x1, y0, y1], ends exclusive; all 0 = full frame; the EXR keeps the full display window").flag());
    // Dicing subdivision surfaces.
    rows.push_back(row("shading_rate", "dicing", &R::dicing, &DicingSettings::shading_rate).range(0.05, 64).unit("pixels")
                       .doc("micropolygon edge length on subdivision surfaces: each control edge is diced into segments of about this many pixels, projected").id(deep | cache).flag());
    rows.push_back(row("ray_level", "dicing", &R::dicing, &DicingSettings::ray_level).range(0, 6).unit("levels")
                       .doc("subdivision level of the coarse tessellation that secondary rays trace (the fine one is never coarser)").id(deep | rad | cache).flag());
    rows.push_back(row("max_level", "dicing", &R::dicing, &DicingSettings::max_level).range(1, 8).unit("levels")
                       .doc("cap on the fine tessellation: at most 2^max_level segments per control edge").id(deep | cache).flag());
    // Lighting.
    rows.push_back(row("memory_budget", "dicing", &R::dicing, &DicingSettings::memory_budget).range(0.001, 1e6).unit("GiB")
                       .doc("memory generated geometry (fur strands and their BVH) may take; a scene asking for more is refused before growing it").flag());
    rows.push_back(row("light_samples", "lighting", &R::lighting, &LightingSettings::light_samples).range(1, 65536).unit("samples")
                       .doc("stratified samples per area light, emissive mesh and sky, per fragment").flag());
    rows.push_back(row("ray_offset", "lighting", &R::lighting, &LightingSettings::ray_offset).automatic(-1).range(0, kMaxCoordinate)
                       .unit("world").doc("ray-origin offsetting distance; auto = 4x the fine/coarse gap, >= 1e-4 x scene diagonal")
                       .id(rad | cache).flag());
    // Radiosity textures.
    rows.push_back(row("radiosity", "radiosity", &R::radiosity, &RadiositySettings::enabled)
                       .doc("shade gather hits from baked radiosity textures instead of shadow rays").id(cache).flag());
    rows.push_back(row("radiosity_textures", "radiosity", &R::radiosity, &RadiositySettings::folder)
                       .doc("folder to reuse matching textures from, or to save new ones in; empty = bake in memory").flag());
    rows.push_back(row("radiosity_texel", "radiosity", &R::radiosity, &RadiositySettings::texel).automatic(0).range(0, kMaxCoordinate)
                       .unit("world").doc("lattice spacing on every triangle; auto = scene diagonal / 128").id(rad | cache).flag());
    rows.push_back(row("radiosity_light_samples", "radiosity", &R::radiosity, &RadiositySettings::light_samples).automatic(0).range(0, 65536)
                       .unit("samples").doc("light samples per lattice point when baking; auto = render.light_samples").id(rad | cache).flag());
    // The gather.
    rows.push_back(row("gi", "gather", &R::indirect, &IndirectSettings::gi).choices({"none", "brute", "cache"})
                       .doc("indirect light: none (direct only), brute (gather at every fragment), cache (irradiance cache)").flag());
    rows.push_back(row("ao", "gather", &R::indirect, &IndirectSettings::ao).doc("ambient occlusion only: the beauty is the AO").id(cache).flag());
    rows.push_back(row("rays", "gather", &R::indirect, &IndirectSettings::rays).range(1, 1 << 20).unit("rays")
                       .doc("rays per gather, an M x N cosine-stratified grid, M = round(sqrt(rays/pi))").id(cache).flag());
    rows.push_back(row("ao_distance", "gather", &R::indirect, &IndirectSettings::ao_distance).automatic(-1).range(0, kMaxCoordinate)
                       .unit("world").doc("occluders farther than this do not count; auto = 10 % of the scene diagonal; 0 = unlimited")
                       .id(cache).flag());
    rows.push_back(row("ao_falloff", "gather", &R::indirect, &IndirectSettings::ao_falloff).range(0, 100)
                       .doc("occlusion of a hit at distance t is (1 - t/ao_distance)^falloff; 0 = full within the distance").id(cache).flag());
    rows.push_back(row("hit_light_samples", "gather", &R::indirect, &IndirectSettings::hit_light_samples).range(1, 65536).unit("samples")
                       .doc("light samples per area light at gather hits when radiosity textures are off").id(cache).flag());
    rows.push_back(row("concave_angle", "gather", &R::indirect, &IndirectSettings::concave_angle).range(0, 90).unit("degrees")
                       .doc("a gather ray this far from the normal at both ends does not shrink the record radius (TL04)").id(cache).flag());
    // The irradiance cache.
    rows.push_back(row("metric", "cache", &R::cache, &CacheSettings::metric).choices({"tl04", "ward", "hessian"})
                       .doc("record error metric: tl04 (normalised, bounded), ward (1/x, accuracy a) or hessian "
                            "(elliptical records sized by the gather's irradiance Hessian)").id(cache).flag());
    rows.push_back(row("min_spacing", "cache", &R::cache, &CacheSettings::min_spacing).range(0.1, 4096).unit("pixels")
                       .doc("smallest record radius").id(cache).flag());
    rows.push_back(row("max_spacing", "cache", &R::cache, &CacheSettings::max_spacing).range(0.1, 4096).unit("pixels")
                       .doc("largest record radius").id(cache).flag());
    rows.push_back(row("max_angle", "cache", &R::cache, &CacheSettings::max_angle).range(0.1, 90).unit("degrees")
                       .doc("normal deviation at which the normal metric reaches 1").id(cache).flag());
    rows.push_back(row("gradient_limit", "cache", &R::cache, &CacheSettings::gradient_limit).range(0, 1e6)
                       .doc("Weber limit tau: gradient-extrapolated change / E at which the metric reaches 1; 0 = off").id(cache).flag());
    rows.push_back(row("quality", "cache", &R::cache, &CacheSettings::quality).range(0.01, 100)
                       .doc("kappa: every TL04 metric is scaled by it; smaller = fewer records").id(cache).flag());
    rows.push_back(row("min_weight", "cache", &R::cache, &CacheSettings::min_weight).range(1e-6, 100)
                       .doc("a lookup misses when the weights sum below this (TL04)").id(cache).flag());
    rows.push_back(row("accuracy", "cache", &R::cache, &CacheSettings::accuracy).range(1e-3, 10)
                       .doc("Ward's a").id(cache).flag());
    rows.push_back(row("gradients", "cache", &R::cache, &CacheSettings::gradients)
                       .doc("extrapolate records with their gradients").id(cache).flag());
    rows.push_back(row("neighbour_clamp", "cache", &R::cache, &CacheSettings::neighbour_clamp)
                       .doc("R_new <= R_j + |p_new - p_j| (Krivanek et al. 2006)").id(cache).flag());
    rows.push_back(row("light_parts", "cache", &R::cache, &CacheSettings::light_parts)
                       .doc("records keep their bounce light per light and are placed as if every light were white at "
                            "intensity 1, so a light's colour or intensity edit rescales it exactly (the lighting tool's default)")
                       .id(cache));
    rows.push_back(row("radius_scale", "cache", &R::cache, &CacheSettings::radius_scale).range(0.01, 100)
                       .doc("R = radius_scale x d_min (TL04: 1/2)").id(cache).flag());
    rows.push_back(row("hessian_error", "cache", &R::cache, &CacheSettings::hessian_error).range(1e-5, 10)
                       .doc("hessian metric: relative second-order error at a record's edge; radii sqrt(2 e / |lambda|)")
                       .id(cache).flag());
    rows.push_back(row("max_anisotropy", "cache", &R::cache, &CacheSettings::max_anisotropy).range(1, 100)
                       .doc("hessian metric: the long radius is at most this many times the short one").id(cache).flag());
    rows.push_back(row("min_rays", "cache", &R::cache, &CacheSettings::min_rays).range(0, 1 << 20).unit("rays")
                       .doc("adaptive records: a record first gathers this many rays and gathers render.rays only when "
                            "that estimate is noisier than ray_noise; 0 = every record gathers render.rays").id(cache).flag());
    rows.push_back(row("ray_noise", "cache", &R::cache, &CacheSettings::ray_noise).range(1e-4, 10)
                       .doc("relative standard error (estimated from the gather's strata) at which a record's first "
                            "gather is kept").id(cache).flag());
    rows.push_back(row("refine", "cache", &R::cache, &CacheSettings::refine).range(0, 100)
                       .doc("per-fragment refinement: a fragment whose covering records' extrapolated values spread "
                            "(weighted relative standard deviation) above this gets a gather of its own; 0 = off").flag());
    rows.push_back(row("refine_band", "cache", &R::cache, &CacheSettings::refine_band).range(1, 100)
                       .doc("per-fragment refinement: a refined fragment's own gather replaces the interpolation wholly "
                            "only once the records' spread reaches this many times `refine`; below that the two are "
                            "blended in proportion, so a fragment crossing the threshold changes gradually (less "
                            "popping in a shot, docs/animation.md); 1 = a hard switch").flag());
    rows.push_back(row("refine_rays", "cache", &R::cache, &CacheSettings::refine_rays).range(0, 1 << 20).unit("rays")
                       .doc("rays of a refined fragment's own gather; 0 = render.rays").flag());
    rows.push_back(row("displaced_records", "cache", &R::cache, &CacheSettings::displaced_records)
                       .choices({"undisplaced", "displaced"})
                       .doc("where records of displaced surfaces live: on the un-displaced surface (rays still leave the "
                            "displaced one) or on the displaced one").id(cache).flag());
    rows.push_back(row("displacement_near", "cache", &R::cache, &CacheSettings::displacement_near).range(0, 1e6)
                       .unit("displacement bounds")
                       .doc("records on the un-displaced surface: gather hits nearer than this many displacement bounds (the "
                            "surface's own bumps) neither shrink a record's radius nor steepen its gradients; 0 = off")
                       .id(cache).flag());
    rows.push_back(row("refine_tilt", "cache", &R::cache, &CacheSettings::refine_tilt).range(0, 180).unit("degrees")
                       .doc("records on the un-displaced surface: a fragment whose displaced normal tilts from the "
                            "un-displaced one by more than this gets a gather of its own (refine_rays); 0 = off").flag());
    rows.push_back(row("temporal_tolerance", "cache", &R::cache, &CacheSettings::temporal_tolerance).range(0, 100)
                       .doc("frames of a shot: a record kept from an earlier frame is gathered again (or re-shaded) once what "
                            "changed in its view may have moved its irradiance by more than this fraction of it; 0 = only "
                            "when nothing it sees changed").flag());
    rows.push_back(row("temporal_refine_reuse", "cache", &R::cache, &CacheSettings::temporal_refine_reuse).range(0, 4)
                       .unit("pixels")
                       .doc("frames of a shot: a fragment that refinement gathers for reuses the rays of the nearest "
                            "earlier frame's refinement gather within this many pixel footprints of it on its surface, "
                            "tracing again only its near rays (docs/animation.md); 0 = off").flag());
    rows.push_back(row("temporal_filter", "cache", &R::cache, &CacheSettings::temporal_filter).range(0, 0.99)
                       .doc("frames of a shot: a record gathered again keeps this share of its previous value (an "
                            "exponential filter along its anchor: less flicker, some lag); 0 = off").flag());
    rows.push_back(row("shading_reach", "cache", &R::cache, &CacheSettings::shading_reach).range(1, 10)
                       .doc("the shading pass lets records reach this much farther (kappa / reach)").flag());
    // Shading.
    rows.push_back(row("light_per_channel", "shading", &R::shading, &ShadingSettings::light_per_channel)
                       .doc("cached indirect light as three (radiance, direction) pairs, one per RGB channel").flag());
    rows.push_back(row("layers", "shading", &R::shading, &ShadingSettings::layers).choices({"standard", "components"})
                       .doc("components adds the beauty's parts for compositing: emission, diffuse and specular direct "
                            "(also per light) and indirect, background, reflection, refraction, and object and material ids "
                            "(docs/shading.md)")
                       .flag());
    rows.push_back(row("deep_colour", "shading", &R::shading, &ShadingSettings::deep_colour)
                       .doc("the deep file of --deep-out also holds each fragment's shaded colour (R, G, B, premultiplied) "
                            "with A as the alpha that over-compositing in depth order needs (its coverage moves to the "
                            "coverage channel): Nuke's deep tools flatten it to the beauty (docs/architecture.md, deep file)").flag());
    rows.push_back(row("specular_depth", "shading", &R::shading, &ShadingSettings::specular_depth).range(0, 16).unit("bounces")
                       .doc("mirror and glass bounces a path from the camera follows (reflections and refractions; 0 = "
                            "mirrors and glass show only what their diffuse and glossy lobes reflect)").flag());
    rows.push_back(row("indirect_at_specular_hits", "shading", &R::shading, &ShadingSettings::indirect_at_specular_hits)
                       .choices({"cache", "radiosity"})
                       .doc("light at the surfaces mirrors and glass show: cache = direct light plus the bounce light of "
                            "records the gathering pass makes for them (brute force gathers there); radiosity = the "
                            "radiosity textures' direct light only, no gathers").flag());
    // Threads and tiles: never change the image (docs/parallel.md).
    rows.push_back(row("threads", "parallel", &R::parallel, &ParallelSettings::threads).range(0, 4096).unit("threads")
                       .doc("worker threads; 0 = all cores").flag());
    rows.push_back(row("tile_size", "parallel", &R::parallel, &ParallelSettings::tile_size).range(1, 4096).unit("pixels")
                       .doc("tile (bucket) edge").flag());
    rows.push_back(row("tile_order", "parallel", &R::parallel, &ParallelSettings::tile_order).choices({"rows", "spiral"})
                       .doc("order threads take tiles in (spiral: centre first)").flag());
    rows.push_back(row("cache_sharing", "parallel", &R::parallel, &ParallelSettings::cache_sharing).choices({"shared", "per-thread"})
                       .doc("one shared cache, or private caches per tile merged between sub-passes").flag());
    rows.push_back(row("preview", "parallel", &R::parallel, &ParallelSettings::preview)
                       .doc("progressive gather-and-shade: the image is rewritten after each sub-pass").flag());
    ParamTable table;
    for (auto& r : rows) {
        // A switch that is on by default is turned off on the command line.
        if (r.p.type == ParamType::Bool && !r.p.flag.empty() && r.p.default_value() == true) r.p.flag = "--no-" + r.p.flag.substr(2);
        table.push_back(std::move(r.p));
    }
    return table;
}

std::string type_name(const Param& p) {
    switch (p.type) {
        case ParamType::Int: return "integer";
        case ParamType::UInt64: return "unsigned integer";
        case ParamType::Float: return "number";
        case ParamType::FloatAuto: return "number or \"auto\"";
        case ParamType::Bool: return "boolean";
        case ParamType::Enum: return "enum";
        case ParamType::Path: return "path";
        case ParamType::Vec3: return "[x, y, z]";
        case ParamType::IntList: return fmt::format("{} integers", p.count);
        case ParamType::FloatList: return fmt::format("{} numbers", p.count);
    }
    return "";
}

/// A number checked as a float: finite, representable, inside [lo, hi].
float check_float(const json& v, double lo, double hi, const std::string& sub, const ParamFail& fail) {
    return json_float(v, lo, hi, [&](const std::string& m) { fail(sub, m); });
}

int64_t check_int(const json& v, double lo, double hi, const std::string& sub, const ParamFail& fail) {
    return json_integer(v, lo, hi, [&](const std::string& m) { fail(sub, m); });
}

}  // namespace

json Param::default_value() const { return get(Scene{}); }

const ParamTable& scene_params() {
    static const ParamTable table = make_table();
    return table;
}

const Param* find_param(const ParamTable& table, const std::string& key) {
    for (const Param& p : table)
        if (p.key == key) return &p;
    return nullptr;
}

json check_param(const Param& p, const json& v, const ParamFail& fail) {
    switch (p.type) {
        case ParamType::Int: return check_int(v, p.lo, p.hi, "", fail);
        case ParamType::UInt64:
            if (!v.is_number_unsigned() && !(v.is_number_integer() && v.get<int64_t>() >= 0))
                fail("", fmt::format("expected a non-negative integer, got {}", v.is_number() ? v.dump() : json_type_name(v)));
            return v.get<uint64_t>();
        case ParamType::FloatAuto:
            if (v.is_string() && v.get<std::string>() == "auto") return v;
            [[fallthrough]];
        case ParamType::Float: return check_float(v, p.lo, p.hi, "", fail);
        case ParamType::Bool:
            if (!v.is_boolean()) fail("", fmt::format("expected true or false, got {}", json_type_name(v)));
            return v;
        case ParamType::Enum:
        case ParamType::Path: {
            if (!v.is_string()) fail("", fmt::format("expected a string, got {}", json_type_name(v)));
            std::string s = v.get<std::string>();
            if (p.type == ParamType::Enum && std::find(p.choices.begin(), p.choices.end(), s) == p.choices.end())
                fail("", fmt::format("unknown value \"{}\" (valid: {})", s, fmt::join(p.choices, ", ")));
            return v;
        }
        case ParamType::Vec3:
        case ParamType::FloatList:
        case ParamType::IntList: {
            const bool floats = p.type != ParamType::IntList;
            size_t n = p.type == ParamType::Vec3 ? 3 : p.count;
            if (!v.is_array() || v.size() != n)
                fail("", fmt::format("expected an array of {} {}, got {}{}", n, floats ? "numbers" : "integers",
                                     json_type_name(v), v.is_array() ? fmt::format(" of {}", v.size()) : ""));
            json out = json::array();
            for (size_t i = 0; i < n; ++i) {
                std::string sub = "/" + std::to_string(i);
                if (floats) out.push_back(check_float(v[i], p.lo, p.hi, sub, fail));
                else out.push_back(check_int(v[i], p.lo, p.hi, sub, fail));
            }
            return out;
        }
    }
    return v;
}

json param_values(const Scene& scene, unsigned mask, const ParamTable& table) {
    json out = json::object();
    for (const Param& p : table)
        if (mask == ~0u || (p.identity & mask)) out[p.key] = p.get(scene);
    return out;
}

std::vector<std::string> param_differences(const json& was, const json& now) {
    std::vector<std::string> out;
    for (const auto& [key, value] : now.items()) {
        if (!was.contains(key)) out.push_back(fmt::format("{}: (not recorded) -> {}", key, value.dump()));
        else if (was[key] != value) out.push_back(fmt::format("{}: {} -> {}", key, was[key].dump(), value.dump()));
    }
    for (const auto& [key, value] : was.items())
        if (!now.contains(key)) out.push_back(fmt::format("{}: {} -> (not a parameter)", key, value.dump()));
    return out;
}

std::string identity_names(unsigned mask) {
    std::vector<std::string> n;
    if (mask & kDeepIdentity) n.push_back("deep");
    if (mask & kRadiosityIdentity) n.push_back("radiosity");
    if (mask & kCacheIdentity) n.push_back("cache");
    return n.empty() ? "image" : fmt::format("{}", fmt::join(n, ","));
}

json params_listing(const ParamTable& table) {
    json out = json::array();
    for (const Param& p : table) {
        json j = {{"key", p.key}, {"stage", p.stage}, {"type", type_name(p)}, {"default", p.default_value()},
                  {"unit", p.unit}, {"doc", p.doc}, {"identity", identity_names(p.identity)}, {"flag", p.flag}};
        if (p.type == ParamType::Enum) j["choices"] = p.choices;
        if (p.lo != p.hi) j["range"] = {p.lo, p.hi};
        if (p.required) j["required"] = true;
        if (p.animatable) j["animatable"] = true;
        out.push_back(j);
    }
    return out;
}

std::string params_markdown(const ParamTable& table) {
    std::string s = "| key | type | default | range | unit | invalidates | animatable | CLI | meaning |\n|---|---|---|---|---|---|---|---|---|\n";
    for (const Param& p : table) {
        std::string range = p.type == ParamType::Enum ? fmt::format("{}", fmt::join(p.choices, ", "))
                            : p.lo != p.hi          ? fmt::format("{:g} .. {:g}", p.lo, p.hi)
                                                    : "";
        std::string def = p.required ? "required" : p.default_value().dump();
        s += fmt::format("| `{}` | {} | `{}` | {} | {} | {} | {} | {} | {} |\n", p.key, type_name(p), def, range, p.unit,
                         identity_names(p.identity), p.animatable ? "yes" : "", p.flag.empty() ? "" : "`" + p.flag + "`", p.doc);
    }
    const json& items = animatable_item_keys();
    s += "\nAnimatable keys of the other items (keyframes, docs/animation.md):\n\n";
    for (const auto& [section, keys] : items.items())
        s += fmt::format("- `{}`: {}\n", section, fmt::format("`{}`", fmt::join(keys.get<std::vector<std::string>>(), "`, `")));
    return s;
}

const json& animatable_item_keys() {
    static const json keys = {
        {"lights", {"color", "intensity", "position", "direction", "cone_angle", "cone_falloff", "corner", "edge_u", "edge_v", "rotation"}},
        {"materials", {"color", "emission", "specular", "roughness", "bump_strength"}},
        {"objects.transform", {"translate", "rotate", "scale"}}};
    return keys;
}

bool animatable_pointer(const std::string& ptr) {
    std::vector<std::string> parts;
    for (size_t at = 1; at <= ptr.size();) {
        const size_t next = std::min(ptr.find('/', at), ptr.size());
        parts.push_back(ptr.substr(at, next - at));
        at = next + 1;
    }
    const auto listed = [](const char* section, const std::string& key) {
        const json& k = animatable_item_keys()[section];
        return std::find(k.begin(), k.end(), key) != k.end();
    };
    if (parts.size() == 2 && parts[0] == "camera") {
        const Param* p = find_param(scene_params(), "camera." + parts[1]);
        return p && p->animatable;
    }
    if (parts.size() == 3 && parts[0] == "lights") return listed("lights", parts[2]);
    if (parts.size() == 3 && parts[0] == "materials") return listed("materials", parts[2]);
    if (parts.size() == 4 && parts[0] == "objects" && parts[2] == "transform") return listed("objects.transform", parts[3]);
    return false;
}

}  // namespace bounce
