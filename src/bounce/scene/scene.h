// The scene as plain data: camera, lights, materials, objects (with both tessellations) and
// render settings. Loaded from a JSON scene file or a bare glTF file (scene_load.h); built
// into ray-tracing structures later (accel/). Every parameter has one name, documented in
// docs/scene-format.md, shared by the JSON file, `--set` and the stats.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "bounce/core/math.h"
#include "bounce/geometry/camera.h"
#include "bounce/geometry/fur.h"
#include "bounce/geometry/mesh.h"
#include "bounce/config/settings.h"
#include "bounce/scene/shot.h"

namespace bounce {

/// A float RGB lat-long image (the textured sky dome); +Y is up, u grows with azimuth.
struct LatLongMap {
    int width = 0, height = 0;
    std::vector<float> rgb;  ///< width*height*3, row 0 at the zenith
    Color lookup(const Vec3& dir, float rotation_deg) const;
    /// The texel at (u, v) in [0, 1]^2 (u across, v down from row 0), nearest; clamped at the edges.
    Color at_uv(float u, float v) const;
};

/// A single-channel texture of opacity (a cutout's alpha), read whole at load and looked up
/// bilinearly with periodic wrap, as the colour texture is (uv (0, 0) is the image's bottom left).
struct OpacityMap {
    int width = 0, height = 0;
    std::vector<uint16_t> texels;  ///< width*height, row 0 at the top, 65535 = opaque (8-bit values exact)
    uint64_t hash = 0;             ///< of its size and texels (BVH parts built with it are keyed by it)
    float at(const Vec2& uv) const;
};

/// An emission texture (glTF's emissiveTexture, the scene file's emission_texture): linear RGB
/// read whole at load, so light sampling, gathers and the camera all see the same radiance,
/// looked up as the opacity map is (bilinear, periodic, uv (0, 0) at the image's bottom left).
struct EmissionMap {
    int width = 0, height = 0;
    std::vector<float> rgb;  ///< width*height*3, row 0 at the top
    Color peak{0};           ///< the brightest texel's value per channel
    Color at(const Vec2& uv) const;
};

/// Where a material's textures are read (KHR_texture_transform), in image space as glTF
/// writes it (s = u, t = 1 - v, t down): (s', t') = offset + R(rotation) (scale x s, scale y t),
/// R turning counter-clockwise in the image by `rotation` radians. One per material: every
/// texture of the material is read through it.
struct UvTransform {
    Vec2 offset{0, 0};
    float rotation = 0;
    Vec2 scale{1, 1};
    bool identity() const { return offset == Vec2{0, 0} && rotation == 0 && scale == Vec2{1, 1}; }
    bool operator==(const UvTransform&) const = default;
    /// A mesh uv moved to the uv its textures are read at.
    Vec2 apply(const Vec2& uv) const { return identity() ? uv : transformed(uv); }
    Vec2 transformed(const Vec2& uv) const;  ///< apply() of a transform that is not the identity
};

/// How a material's opacity cuts its surface (glTF's alphaMode). Opaque: it is not read. Mask:
/// where it is below the cutoff the surface is not there for any ray. Blend: it is the share of
/// a pixel the surface covers and the chance that a secondary ray meeting it stops there.
enum class AlphaMode : uint8_t { Opaque, Mask, Blend };

enum class LightType { Point, Spot, Distant, Quad, Sky, Mesh };

struct Light {
    LightType type = LightType::Point;
    std::string name;          ///< "name" in the scene file, else "lightN"; a mesh light's is its object's
    Color color{1};            ///< point/spot: intensity (W/sr); distant: irradiance; quad/sky: radiance
    Vec3 position{0};          ///< point, spot
    Vec3 direction{0, -1, 0};  ///< spot: where it points; distant: direction light travels
    float cone_angle = 30;     ///< spot: half-angle of full intensity, degrees
    float cone_falloff = 5;    ///< spot: width of the smooth edge beyond cone_angle, degrees
    float cosine_power = 0;    ///< spot: intensity x cos(angle from the axis)^cosine_power; 0 = even across the cone (Cycles 3.4's spot: 1)
    Vec3 corner{0}, edge_u{1, 0, 0}, edge_v{0, 0, 1};  ///< quad; emits towards edge_u x edge_v
    std::shared_ptr<const LatLongMap> sky_map;         ///< sky: optional texture (times color)
    /// quad: radiance texture over the quad (u along edge_u, v along edge_v, times color);
    /// spot: a slide projected over its outer cone (a gobo). Null = none.
    std::shared_ptr<const LatLongMap> texture;
    /// spot: barn doors, the largest angles (degrees, 0-90) from the axis towards the spot's
    /// left, right, top and bottom (right = direction x +Y; top = right x direction) it lights.
    std::array<float, 4> barn_doors{90, 90, 90, 90};
    float sky_rotation = 0;  ///< sky: rotation about +Y, degrees
    uint32_t object = 0;     ///< mesh: the object whose emissive faces emit
    /// Light linking, per object index (scene file: "light_link"): 1 = lit by this light.
    /// Empty = every object.
    std::vector<uint8_t> lit;
    /// Shadow linking (scene file: "shadow_link"): 1 = casts this light's shadows. Empty =
    /// every object that casts shadows at all (Object::visible_to.shadows).
    std::vector<uint8_t> shadowed_by;
    /// Which of the ray-mask bits for linked shadows this light's shadow rays use (-1: none).
    int shadow_slot = -1;
    bool lights(uint32_t object_index) const { return lit.empty() || lit[object_index]; }
};

/// How many lights may have a shadow link (one Embree ray-mask bit each).
inline constexpr int kMaxShadowLinkedLights = 28;

struct Material {
    std::string name;
    Color color{0.7f};          ///< diffuse albedo (multiplied by the texture if any)
    std::string color_texture;  ///< absolute path, empty = none
    Color emission{0};          ///< emitted radiance; nonzero makes faces area lights
    /// Absolute path, empty = none: multiplies `emission` (read whole into emission_map).
    std::string emission_texture;
    std::shared_ptr<const EmissionMap> emission_map;
    Color specular{0};       ///< GGX lobe's reflectance at normal incidence (F0); 0 = no lobe
    float roughness = 0.5f;  ///< GGX roughness (alpha = roughness^2), in (0, 1]
    /// glTF's metallic-roughness texture (absolute path, empty = none): where it is given,
    /// roughness x its green channel is the roughness and metallic x its blue channel the
    /// metalness m, so the albedo is color x (1 - m) and F0 = 0.04 (1 - m) + color x m
    /// (`specular` is not read).
    std::string metallic_roughness_texture;
    float metallic = 1;
    std::string bump_texture;    ///< height map (texture units per uv unit x bump_strength)
    std::string normal_texture;  ///< tangent-space normal map (used when there is no bump map)
    float bump_strength = 1.0f;  ///< scales the bump height or the normal map's tilt; 0 = off
    std::string ao_texture;      ///< baked occlusion (bounce bake-ao) multiplying the indirect light and AO
    /// An ideal mirror's reflectance (a conductor: the same at every angle, tinted for metals);
    /// 0 = none. The rest of the light (1 - mirror) meets the surface's other lobes.
    Color mirror{0};
    /// A smooth dielectric (glass, water): Fresnel reflection at index `ior`, and this share of
    /// the light let in is refracted (its tint); 0 = opaque, 1 = clear.
    Color transmission{0};
    float ior = 1.5f;     ///< the dielectric's index of refraction (with transmission)
    Color absorption{0};  ///< inside the dielectric: Beer-Lambert coefficient per world unit
    /// Thin diffuse transmission (glTF's KHR_materials_diffuse_transmission): this share of the
    /// diffuse light leaves by the other side of the surface, tinted by
    /// `diffuse_transmission_color` (not by `color`); the rest is reflected with `color`.
    float diffuse_transmission = 0;
    Color diffuse_transmission_color{1};
    AlphaMode alpha_mode = AlphaMode::Opaque;
    float opacity = 1;  ///< multiplies the opacity texture (glTF: the base colour factor's alpha)
    /// Absolute path, empty = none: its alpha channel, or its only channel (MTL's map_d).
    std::string opacity_texture;
    std::shared_ptr<const OpacityMap> opacity_map;  ///< opacity_texture read (null = none)
    float alpha_cutoff = 0.5f;                      ///< mask: opacity below it is cut away
    UvTransform uv_transform;                       ///< where every texture of the material is read
    uint8_t uv_set = 0;                             ///< a mesh file's uv set its textures read (glTF texCoord)
    /// A mesh file's material: what it carries that bounce does not read ("KHR_materials_sheen", ...).
    std::vector<std::string> unread;
    bool is_cutout() const { return alpha_mode != AlphaMode::Opaque; }
    /// Opacity at uv (1 for opaque materials).
    float opacity_at(const Vec2& uv) const {
        if (alpha_mode == AlphaMode::Opaque) return 1;
        return opacity_map ? opacity * opacity_map->at(uv_transform.apply(uv)) : opacity;
    }
    /// Emitted radiance at uv.
    Color emission_at(const Vec2& uv) const { return emission_map ? emission * emission_map->at(uv_transform.apply(uv)) : emission; }
    bool is_dielectric() const { return transmission.x > 0 || transmission.y > 0 || transmission.z > 0; }
    bool is_specular() const { return is_dielectric() || mirror.x > 0 || mirror.y > 0 || mirror.z > 0; }
    bool is_translucent() const { return diffuse_transmission > 0; }
    bool has_specular() const { return specular.x > 0 || specular.y > 0 || specular.z > 0; }
    bool has_bump() const { return bump_strength != 0 && (!bump_texture.empty() || !normal_texture.empty()); }
    /// Every texture file it names, empty or not (for what treats them alike: the mesh cache).
    std::array<std::string*, 7> texture_files() {
        return {
            &color_texture, &bump_texture, &normal_texture, &ao_texture, &opacity_texture, &emission_texture, &metallic_roughness_texture};
    }
    /// The most it emits anywhere (its emission texture's brightest texel).
    Color peak_emission() const { return emission_map ? emission * emission_map->peak : emission; }
    bool is_emissive() const {
        const Color most = peak_emission();
        return most.x > 0 || most.y > 0 || most.z > 0;
    }
};

struct SubdivSurface;

struct Object {
    std::string name;
    TriangleMesh coarse;           ///< traced by all secondary rays
    TriangleMesh fine;             ///< seen by primary visibility (empty = same as coarse)
    int dicing_level = 0;          ///< subdivision surfaces: the fine tessellation's level (0 = not one)
    double dicing_seconds = 0;     ///< time the loader spent dicing it
    float displacement_bound = 0;  ///< largest distance displacement moves a point (0 = none)
    /// Strands grown on the visible surface (null = none); a mover's are grown as it stands at the
    /// shot's first frame and carried to this frame's pose (carry_fur).
    std::shared_ptr<const Fur> fur;
    std::shared_ptr<const SubdivSurface> surface;  ///< subdivision objects: what was diced (null = none)
    Transform placement;                           ///< the scene file's transform, already applied to both tessellations
    bool deforms = false;                          ///< its shape changes over the shot (a skin, morph targets), not only its placement
    bool moves = false;                            ///< its placement is keyed or it deforms: its cache records travel with it
    RayVisibility visible_to;
    /// A holdout: where the camera sees it, black with alpha 0, hiding what is behind it.
    bool matte = false;
    /// With motion blur: the visible mesh's vertices at shutter open and close (empty when it
    /// does not move during the shutter, and for rigid movers traced by `shutter_placement`);
    /// camera rays see it in between.
    std::array<std::vector<Vec3>, 2> shutter;
    /// Rigid movers (placement keyed, not deforming; not subdivision surfaces): both
    /// tessellations before `placement` (null fine = none). Ray tracing places them with it, so
    /// a shot's frames move them without building their BVHs again (accel/bvh.h).
    std::shared_ptr<const TriangleMesh> local_coarse, local_fine;
    /// With motion blur, a mover's fur: its control points (as Fur::vertices) at shutter open and
    /// close (empty otherwise), the same strands moved with the object or carried by the skin.
    std::array<std::vector<float>, 2> fur_shutter;
    /// With motion blur, rigid movers with local tessellations: the placement at shutter open and close.
    std::optional<std::array<Transform, 2>> shutter_placement;
    /// An instance (scene file "instances"): it places another object's tessellations, shared
    /// with every placement of it (`local_coarse`, `local_fine`), with `placement`. Its own
    /// `coarse` and `fine` stay empty, so memory grows with prototypes, not placements: read its
    /// triangles through coarse_mesh() / visible_mesh() and its points through to_world().
    bool instance = false;
    /// Loaded only to be placed by instances (scene file "prototype": true): no ray sees it, and
    /// it neither sizes the scene nor holds radiosity.
    bool prototype = false;
    /// An instance's material for every face (its "material"); -1 = the prototype's own.
    int material_override = -1;
    /// An instance's world bounds: of its coarse and of its visible tessellation, placed.
    Bounds instance_bounds, instance_visible_bounds;
    bool has_fine() const { return instance ? local_fine != nullptr : !fine.indices.empty(); }
    /// The tessellation in world space (empty for an instance: use the placed accessors below).
    const TriangleMesh& visible() const { return has_fine() && !instance ? fine : coarse; }
    /// The triangles a hit's `prim` indexes: what secondary rays trace, and what the camera sees.
    const TriangleMesh& coarse_mesh() const { return instance ? *local_coarse : coarse; }
    const TriangleMesh& visible_mesh() const { return instance ? (local_fine ? *local_fine : *local_coarse) : visible(); }
    /// What places coarse_mesh() and visible_mesh() in the world (null: they are in place).
    const Transform* to_world() const { return instance ? &placement : nullptr; }
    /// Points of the two tessellations in world space, with an instance's material override.
    SurfacePoint coarse_point(uint32_t prim, float u, float v) const {
        return with_material(surface_point(coarse_mesh(), to_world(), prim, u, v));
    }
    SurfacePoint visible_point(uint32_t prim, float u, float v) const {
        return with_material(surface_point(visible_mesh(), to_world(), prim, u, v));
    }
    /// Triangle `prim`'s material (coarse tessellation).
    uint32_t material_of(uint32_t prim) const {
        return material_override >= 0 ? static_cast<uint32_t>(material_override) : coarse_mesh().face_materials[prim];
    }
    /// Rays may see it (prototypes are only placed).
    bool placed() const { return !prototype; }
    /// World bounds of its coarse and of its visible tessellation.
    Bounds coarse_bounds() const { return instance ? instance_bounds : coarse.bounds(); }
    Bounds visible_mesh_bounds() const { return instance ? instance_visible_bounds : visible().bounds(); }

  private:
    SurfacePoint with_material(SurfacePoint sp) const {
        if (material_override >= 0) sp.material = static_cast<uint32_t>(material_override);
        return sp;
    }
};

/// A file a scene reads and the key that named it ("/objects/2/file", "/materials/wood/color_texture");
/// files a mesh file pulls in (an OBJ's MTL, a glTF's buffers and images) carry its key.
struct SceneInput {
    std::string path;
    std::string pointer;
    uint64_t hash = 0;  ///< file_content_hash, taken at load
};

/// How long loading a scene took (the statistics' first phases): all of it, and of that the
/// mesh files' parsing (or their mesh cache entries' reading).
struct LoadTimes {
    double seconds = 0, mesh_parse_seconds = 0;
};

struct Scene {
    std::string path;  ///< the file it came from
    LoadTimes load_times;
    std::vector<SceneInput> inputs;          ///< every file it reads (not the scene file itself)
    std::vector<std::string> input_folders;  ///< folders it reads (render.radiosity_textures)
    /// What its mesh files' materials carry that bounce does not read, one line per file and
    /// feature ("card.gltf: ignored: emissiveTexture on 3 materials"); front ends show them.
    std::vector<std::string> unread;
    Camera camera;
    std::vector<Light> lights;
    std::vector<Material> materials;
    std::vector<Object> objects;
    RenderSettings render;
    /// The effective scene description after overrides, at the frame (for metadata and fingerprints).
    nlohmann::json description;
    /// The description before keyed values were taken at the frame (null for a still).
    nlohmann::json keyed;
    ShotSettings shot;  ///< the scene file's shot (frames, fps)
    double frame = 1;   ///< the frame this scene is

    Bounds bounds() const;          ///< of the coarse tessellation (what rays trace)
    bool objects_move() const;      ///< some object moves over the shot (Object::moves)
    Bounds visible_bounds() const;  ///< of everything the camera can see (fine surfaces, fur)
    /// The length that automatic distances are fractions of (the ray offset, the radiosity texel,
    /// the AO distance): the diagonal of the objects that do not move, or of all when every object
    /// moves. A walking character that sticks out of its set would otherwise change them from
    /// frame to frame, and with them every gather near a contact (flicker in the references too).
    float size() const;
    /// 64-bit hash of the named top-level parts of the effective description ("camera",
    /// "objects" ...): the identity that deep and cache files are checked against.
    /// `without_surface_shading` leaves out the material keys that only change how a surface
    /// reflects light to the camera (specular, roughness, bump and normal maps): cached
    /// irradiance does not depend on them.
    /// Each part's hash includes the content of the files named under it (inputs_hash).
    uint64_t fingerprint(const std::vector<std::string>& parts, bool without_surface_shading = false) const;
    /// fingerprint({"objects", "materials", "lights"}, true) with every light's "color" and
    /// "intensity" left out: records that keep their light parts (scales factored out) serve
    /// any scene of the same unscaled fingerprint exactly, at its own scales.
    uint64_t unscaled_fingerprint() const;
    /// Hash of the content of the input files named under top-level `part` ("objects" ...).
    uint64_t inputs_hash(const std::string& part, bool without_surface_shading = false) const;
    /// The scene file and every file it reads: what no output may overwrite.
    std::vector<std::string> input_paths() const;
    /// What a deep file depends on: the camera and the objects, without the fur keys that only
    /// change how strands are lit (colours, specular, falloff, what rays see them), and with
    /// subdivision surfaces the dicing settings.
    uint64_t visibility_fingerprint() const;
};

}  // namespace bounce
