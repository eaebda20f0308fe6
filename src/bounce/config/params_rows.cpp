// The camera's rows of the parameter table and those of the stages before and after the cache
// (params.h; the cache's are in params_cache.cpp).
#include "bounce/config/param_rows.h"

namespace bounce::param_rows {

namespace {

using R = RenderSettings;
constexpr unsigned deep = kDeepIdentity, rad = kRadiosityIdentity, cache = kCacheIdentity;

/// A camera row of `type` read and written by `get` and `set`; the camera's rows all change
/// primary visibility (caches check the camera's fingerprint).
Row camera_row(const char* key, ParamType type, size_t count, std::function<json(ParamsIn)> get,
               std::function<void(ParamsOut, const json&)> set) {
    Row r;
    r.p.key = std::string("camera.") + key;
    r.p.stage = "camera";
    r.p.type = type;
    r.p.count = count;
    r.p.identity = deep;
    r.p.get = std::move(get);
    r.p.set = std::move(set);
    return r;
}

Row camera_float(const char* key, float Camera::*member) {
    return camera_row(
        key, ParamType::Float, 0, [member](ParamsIn s) -> json { return s.camera.*member; },
        [member](ParamsOut s, const json& v) { s.camera.*member = v.get<float>(); });
}

Row camera_vec3(const char* key, Vec3 Camera::*member, const char* doc, bool required) {
    Row r = camera_row(
        key, ParamType::Vec3, 0,
        [member](ParamsIn s) -> json {
            const Vec3& v = s.camera.*member;
            return json::array({v.x, v.y, v.z});
        },
        [member](ParamsOut s, const json& v) {
            s.camera.*member = {v[0].get<float>(), v[1].get<float>(), v[2].get<float>()};
        });
    r.p.required = required;
    return r.range(-kMaxCoordinate, kMaxCoordinate).unit("world").doc(doc);
}

}  // namespace

void add_camera_rows(std::vector<Row>& rows) {
    rows.push_back(camera_vec3("position", &Camera::position, "where the camera is", true).animate());
    rows.push_back(camera_vec3("look_at", &Camera::look_at, "the point it looks at", true).animate());
    rows.push_back(camera_vec3("up", &Camera::up, "up direction; must not be parallel to the view", false).animate());
    rows.push_back(camera_float("fov", &Camera::fov).range(0.001, 179.999).unit("degrees").doc("vertical field of view").animate());
    Row shutter = camera_row(
        "shutter", ParamType::FloatList, 2,
        [](ParamsIn s) -> json {
            return json::array({s.camera.shutter[0], s.camera.shutter[1]});
        },
        [](ParamsOut s, const json& v) {
            s.camera.shutter = {v[0].get<float>(), v[1].get<float>()};
        });
    rows.push_back(
        shutter.range(-1, 1)
            .unit("frames")
            .doc("[open, close] around the frame's time (close not before open): primary visibility is blurred over it (keyed objects, "
                 "meshes playing a clip and a keyed camera move in it), shading is at the frame's time; "
                 "[0, 0] = no motion blur")
            .animate());
    rows.push_back(camera_float("aperture", &Camera::aperture)
                       .range(0, kMaxCoordinate)
                       .unit("world")
                       .doc("lens diameter (thin lens): depth of field; 0 = pinhole")
                       .animate());
    rows.push_back(camera_float("focus_distance", &Camera::focus_distance)
                       .automatic(0)
                       .range(0, kMaxCoordinate)
                       .unit("world")
                       .doc("distance of the plane in focus along the view; auto = the distance to look_at")
                       .animate());
    Row resolution = camera_row(
        "resolution", ParamType::IntList, 2,
        [](ParamsIn s) -> json {
            return json::array({s.camera.width, s.camera.height});
        },
        [](ParamsOut s, const json& v) { s.camera.width = v[0].get<int>(), s.camera.height = v[1].get<int>(); });
    rows.push_back(resolution.range(1, 65536).unit("pixels").doc("[width, height]; on the CLI WIDTHxHEIGHT").flag("--res"));
}

namespace {

void add_visibility_rows(std::vector<Row>& rows) {
    // Primary visibility and the deep file.
    rows.push_back(row("spp", "visibility", &R::visibility, &VisibilitySettings::spp)
                       .range(1, 4096)
                       .unit("samples")
                       .doc("jittered subsamples per pixel (primary visibility)")
                       .id(deep)
                       .flag());
    rows.push_back(row("seed", "visibility", &R::visibility, &VisibilitySettings::seed)
                       .range(0, 1.8446744073709552e19)
                       .doc("random seed; every random number is a hash of (pixel, sample, dimension, seed)")
                       .id(deep | cache)
                       .flag());
    rows.push_back(row("crop", "visibility", &R::visibility, &VisibilitySettings::crop)
                       .range(0, 65536)
                       .unit("pixels")
                       .doc("[x0, x1, y0, y1], ends exclusive; all 0 = full frame; the EXR keeps the full display window")
                       .flag());
    // Dicing subdivision surfaces.
    rows.push_back(row("shading_rate", "dicing", &R::dicing, &DicingSettings::shading_rate)
                       .range(0.05, 64)
                       .unit("pixels")
                       .doc("micropolygon edge length on subdivision surfaces: each control edge is diced into segments of about this many "
                            "pixels, projected")
                       .id(deep | cache)
                       .flag());
    rows.push_back(row("ray_level", "dicing", &R::dicing, &DicingSettings::ray_level)
                       .range(0, 6)
                       .unit("levels")
                       .doc("subdivision level of the coarse tessellation that secondary rays trace (the fine one is never coarser)")
                       .id(deep | rad | cache)
                       .flag());
    rows.push_back(row("max_level", "dicing", &R::dicing, &DicingSettings::max_level)
                       .range(1, 8)
                       .unit("levels")
                       .doc("cap on the fine tessellation: at most 2^max_level segments per control edge")
                       .id(deep | cache)
                       .flag());
}

void add_lighting_rows(std::vector<Row>& rows) {
    // Lighting.
    rows.push_back(row("memory_budget", "dicing", &R::dicing, &DicingSettings::memory_budget)
                       .range(0.001, 1e6)
                       .unit("GiB")
                       .doc("memory generated geometry (fur strands, tessellated spheres, and their BVHs) may take; a scene asking for "
                            "more is refused before growing it")
                       .flag());
    rows.push_back(row("light_samples", "lighting", &R::lighting, &LightingSettings::light_samples)
                       .range(1, 65536)
                       .unit("samples")
                       .doc("stratified samples per area light, emissive mesh and sky, per fragment")
                       .flag());
    rows.push_back(row("light_pick", "lighting", &R::lighting, &LightingSettings::light_pick)
                       .range(0, 1 << 20)
                       .unit("lights")
                       .doc("a point lit by more point, spot and quad lights than this samples this many of them, each "
                            "chosen by its unshadowed contribution and weighed by its chance (unbiased: direct light and "
                            "radiosity bakes cost the same for 10 000 lights as for this many); 0 = every light")
                       .flag());
    rows.push_back(row("ray_offset", "lighting", &R::lighting, &LightingSettings::ray_offset)
                       .automatic(-1)
                       .range(0, kMaxCoordinate)
                       .unit("world")
                       .doc("ray-origin offsetting distance; auto = 4x the fine/coarse gap, >= 1e-4 x the scene size (the diagonal of what "
                            "does not move)")
                       .id(rad | cache)
                       .flag());
    // Radiosity textures.
    rows.push_back(row("radiosity", "radiosity", &R::radiosity, &RadiositySettings::enabled)
                       .doc("shade gather hits from baked radiosity textures instead of shadow rays")
                       .id(cache)
                       .flag());
    rows.push_back(row("radiosity_textures", "radiosity", &R::radiosity, &RadiositySettings::folder)
                       .doc("folder to reuse matching textures from, or to save new ones in; empty = bake in memory")
                       .flag());
    rows.push_back(row("radiosity_texel", "radiosity", &R::radiosity, &RadiositySettings::texel)
                       .automatic(0)
                       .range(0, kMaxCoordinate)
                       .unit("world")
                       .doc("lattice spacing on every triangle; auto = the scene size / 128")
                       .id(rad | cache)
                       .flag());
    rows.push_back(row("radiosity_light_samples", "radiosity", &R::radiosity, &RadiositySettings::light_samples)
                       .automatic(0)
                       .range(0, 65536)
                       .unit("samples")
                       .doc("light samples per lattice point when baking; auto = render.light_samples")
                       .id(rad | cache)
                       .flag());
    rows.push_back(row("radiosity_small_instances", "radiosity", &R::radiosity, &RadiositySettings::small_instances)
                       .choices({"auto", "hit", "lattice"})
                       .doc("direct light at gather hits on placements none of whose triangles reaches a texel: hit = one shadow "
                            "ray per light where the ray lands (never baked); lattice = the placement's baked lattice; auto = hit "
                            "where a probe of the frame's gathers expects fewer hits than 3 x radiosity_light_samples per triangle")
                       .id(rad | cache)
                       .flag());
}

void add_gather_rows(std::vector<Row>& rows) {
    // The gather.
    rows.push_back(row("gi", "gather", &R::indirect, &IndirectSettings::gi)
                       .choices({"none", "brute", "cache"})
                       .doc("indirect light: none (direct only), brute (gather at every fragment), cache (irradiance cache)")
                       .flag());
    rows.push_back(
        row("ao", "gather", &R::indirect, &IndirectSettings::ao).doc("ambient occlusion only: the beauty is the AO").id(cache).flag());
    rows.push_back(row("rays", "gather", &R::indirect, &IndirectSettings::rays)
                       .range(1, 1 << 20)
                       .unit("rays")
                       .doc("rays per gather, an M x N cosine-stratified grid, M = round(sqrt(rays/pi))")
                       .id(cache)
                       .flag());
    rows.push_back(row("ao_distance", "gather", &R::indirect, &IndirectSettings::ao_distance)
                       .automatic(-1)
                       .range(0, kMaxCoordinate)
                       .unit("world")
                       .doc("occluders farther than this do not count; auto = 10 % of the scene size; 0 = unlimited")
                       .id(cache)
                       .flag());
    rows.push_back(row("ao_falloff", "gather", &R::indirect, &IndirectSettings::ao_falloff)
                       .range(0, 100)
                       .doc("occlusion of a hit at distance t is (1 - t/ao_distance)^falloff; 0 = full within the distance")
                       .id(cache)
                       .flag());
    rows.push_back(row("hit_light_samples", "gather", &R::indirect, &IndirectSettings::hit_light_samples)
                       .range(1, 65536)
                       .unit("samples")
                       .doc("light samples per area light at gather hits when radiosity textures are off")
                       .id(cache)
                       .flag());
    rows.push_back(row("concave_angle", "gather", &R::indirect, &IndirectSettings::concave_angle)
                       .range(0, 90)
                       .unit("degrees")
                       .doc("a gather ray this far from the normal at both ends does not shrink the record radius (TL04)")
                       .id(cache)
                       .flag());
    rows.push_back(row("guided", "gather", &R::indirect, &IndirectSettings::guided)
                       .range(0, 0.95)
                       .doc("per-fragment gathers (brute force, cache refinement): share of their rays spread over 32 direction bins "
                            "by a guide (brute force: a pilot gather per 8x8 pixels; refinement: the covering records); 0 = even")
                       .flag());
}

}  // namespace

void add_pipeline_rows(std::vector<Row>& rows) {
    add_visibility_rows(rows);
    add_lighting_rows(rows);
    add_gather_rows(rows);
}

void add_output_rows(std::vector<Row>& rows) {
    // Shading.
    rows.push_back(row("light_per_channel", "shading", &R::shading, &ShadingSettings::light_per_channel)
                       .doc("cached indirect light as three (radiance, direction) pairs, one per RGB channel")
                       .flag());
    rows.push_back(row("layers", "shading", &R::shading, &ShadingSettings::layers)
                       .choices({"standard", "components"})
                       .doc("components adds the beauty's parts for compositing: emission, diffuse and specular direct "
                            "(also per light) and indirect, background, reflection, refraction, and object and material ids "
                            "(docs/shading.md)")
                       .flag());
    rows.push_back(row("deep_colour", "shading", &R::shading, &ShadingSettings::deep_colour)
                       .doc("the deep file of --deep-out also holds each fragment's shaded colour (R, G, B, premultiplied) "
                            "with A as the alpha that over-compositing in depth order needs (its coverage moves to the "
                            "coverage channel): Nuke's deep tools flatten it to the beauty (docs/architecture.md, deep file)")
                       .flag());
    rows.push_back(row("specular_depth", "shading", &R::shading, &ShadingSettings::specular_depth)
                       .range(0, 16)
                       .unit("bounces")
                       .doc("mirror and glass bounces a path from the camera follows (reflections and refractions; 0 = "
                            "mirrors and glass show only what their diffuse and glossy lobes reflect)")
                       .flag());
    rows.push_back(row("indirect_at_specular_hits", "shading", &R::shading, &ShadingSettings::indirect_at_specular_hits)
                       .choices({"cache", "radiosity"})
                       .doc("light at the surfaces mirrors and glass show: cache = direct light plus the bounce light of "
                            "records the gathering pass makes for them (brute force gathers there); radiosity = the "
                            "radiosity textures' direct light only, no gathers")
                       .flag());
    // Threads and tiles: never change the image (docs/parallel.md).
    rows.push_back(row("threads", "parallel", &R::parallel, &ParallelSettings::threads)
                       .range(0, 4096)
                       .unit("threads")
                       .doc("worker threads; 0 = all cores")
                       .flag());
    rows.push_back(row("tile_size", "parallel", &R::parallel, &ParallelSettings::tile_size)
                       .range(1, 4096)
                       .unit("pixels")
                       .doc("tile (bucket) edge")
                       .flag());
    rows.push_back(row("tile_order", "parallel", &R::parallel, &ParallelSettings::tile_order)
                       .choices({"rows", "spiral"})
                       .doc("order threads take tiles in (spiral: centre first)")
                       .flag());
    rows.push_back(row("cache_sharing", "parallel", &R::parallel, &ParallelSettings::cache_sharing)
                       .choices({"shared", "per-thread"})
                       .doc("one shared cache, or private caches per tile merged between sub-passes")
                       .flag());
    rows.push_back(row("preview", "parallel", &R::parallel, &ParallelSettings::preview)
                       .doc("progressive gather-and-shade: the image is rewritten after each sub-pass")
                       .flag());
}

}  // namespace bounce::param_rows
