// Materials at a surface point: albedo (colour x texture), emission, the GGX glossy lobe and
// the shading normal after bump or normal mapping. Textures go through OpenImageIO's
// TextureSystem (mipmapped, filtered by the pixel's footprint at visible points).
#pragma once

#include <cstdint>
#include <vector>

#include "bounce/core/math.h"
#include "bounce/scene/scene.h"

#include <OpenImageIO/oiioversion.h>
OIIO_NAMESPACE_BEGIN
class TextureSystem;
OIIO_NAMESPACE_END

namespace bounce {

/// A material evaluated where the camera sees it: everything a surface shader needs.
struct SurfaceShading {
    Color albedo{0};
    Color specular{0};  ///< GGX F0 (0 = no glossy lobe)
    float roughness = 1;
    Vec3 normal{0, 0, 1};  ///< shading normal after bump / normal mapping (unit; = n without)
    float occlusion = 1;   ///< the material's baked AO (ao_texture), multiplying indirect light and AO
    /// A thin translucent surface's diffuse transmittance (Material::diffuse_transmission x its
    /// colour): light arriving through the other side leaves with this over pi. 0 elsewhere.
    Color translucency{0};
};

class Materials {
  public:
    explicit Materials(const Scene& scene);
    ~Materials();
    Materials(const Materials&) = delete;
    Materials& operator=(const Materials&) = delete;

    /// Albedo at uv, unfiltered: the diffuse reflectance (a translucent material's share of it
    /// that is not transmitted).
    Color albedo(uint32_t material, const Vec2& uv) const;
    /// Diffuse transmittance at uv (SurfaceShading::translucency), unfiltered.
    Color translucency(uint32_t material, const Vec2& uv) const;
    /// What secondary rays (gathers, radiosity textures) see at a point they reach: albedo x
    /// its vertex colour x base_share (a mirror or glass surface reflects little diffusely).
    Color secondary_albedo(const SurfacePoint& sp) const;
    /// The diffuse transmittance secondary rays see there (0 on an opaque material).
    Color secondary_translucency(const SurfacePoint& sp) const {
        return scene_.materials[sp.material].is_translucent() ? translucent_share(sp) : Color(0);
    }
    /// The vertex colour (glTF's COLOR_0) of object `object`'s visible triangle `prim` at `p`.
    Color vertex_color(uint32_t object, uint32_t prim, const Vec3& p) const;
    /// Emitted radiance at uv (its emission texture read whole at load: Material::emission_at).
    Color emission(uint32_t material, const Vec2& uv) const { return scene_.materials[material].emission_at(uv); }

    /// The material at a visible point: triangle `prim` of object `object`'s visible mesh, at
    /// `p` and `uv` (the albedo times the vertex colour there), with interpolated normal `n` and pixel footprint `footprint` (world units;
    /// the texture filter width). Bump maps displace by bump_strength x texture value (world units); normal maps are tangent-space, tilted
    /// by bump_strength.
    SurfaceShading surface(uint32_t material, uint32_t object, uint32_t prim, const Vec3& p, const Vec2& uv, const Vec3& n,
                           float footprint) const;

  private:
    /// secondary_translucency() of a translucent material.
    Color translucent_share(const SurfacePoint& sp) const;
    /// Texture file names as OpenImageIO unique strings (ustring::c_str()), made once here:
    /// making them per lookup would take the global string table's lock every time.
    struct TextureNames {
        const char* color = nullptr;
        const char* bump = nullptr;
        const char* normal = nullptr;
        const char* ao = nullptr;
        const char* metallic_roughness = nullptr;
    };
    /// Colour x colour texture at texture uv `st` (the material's uv transform applied), with
    /// a filter of (du, dv) uv units.
    Color base_colour(uint32_t material, const Vec2& st, float du, float dv) const;
    /// glTF's metalness at `st` (metallic x the texture's blue channel): -1 without a texture.
    float metalness(uint32_t material, const Vec2& st, float du, float dv, float* roughness = nullptr) const;
    const Scene& scene_;
    OIIO::TextureSystem* textures_ = nullptr;
    std::vector<TextureNames> names_;
};

/// Fresnel reflectance of a smooth dielectric boundary for unpolarised light arriving at cosine
/// `cos_i` to the normal on its side; `eta` = n(far side) / n(near side). 1 beyond the critical angle.
float fresnel_dielectric(float cos_i, float eta);
/// Mirror direction of unit `d` about unit `n`.
inline Vec3 reflect(const Vec3& d, const Vec3& n) { return d - n * (2 * dot(d, n)); }
/// Snell's refraction of unit `d` through unit `n` (facing against d), `eta` = n(near) / n(far);
/// false under total internal reflection.
bool refract(const Vec3& d, const Vec3& n, float eta, Vec3& out);

/// How a surface splits the light arriving at it: an ideal mirror's share (mirror, and a
/// dielectric's Fresnel reflection), the refracted share, and the rest, which its diffuse and
/// glossy lobes reflect. The three sum to 1 per channel.
struct SpecularSplit {
    Color reflect{0}, transmit{0}, base{1};
};
/// At cosine `cos_i` to the normal, arriving from outside the object (`entering`) or inside it.
SpecularSplit specular_split(const Material& m, float cos_i, bool entering);
/// The base share at normal incidence from outside: the albedo scale that secondary rays
/// (gathers, the radiosity bake) see on a mirror or glass surface.
Color base_share(const Material& m);

/// dP/du and dP/dv of triangle `prim` of `mesh` (from its positions and uvs, moved by `xf`
/// when given); false when the mesh has no uvs or they are degenerate there.
bool triangle_tangents(const TriangleMesh& mesh, uint32_t prim, Vec3& dpdu, Vec3& dpdv, const UvTransform* xf = nullptr);

/// Blinn's bump mapping: the normal of the surface P + h n, for height derivatives (dh/du,
/// dh/dv) and tangents dP/du, dP/dv; n unchanged when both derivatives are 0.
Vec3 bumped_normal(const Vec3& n, const Vec3& dpdu, const Vec3& dpdv, float dhdu, float dhdv);

}  // namespace bounce
