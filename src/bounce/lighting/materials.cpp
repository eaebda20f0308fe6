#include "bounce/lighting/materials.h"

#include <OpenImageIO/texture.h>
#include <OpenImageIO/ustring.h>

#include <algorithm>
#include <cmath>

namespace bounce {

Materials::Materials(const Scene& scene) : scene_(scene) {
    bool any = false;
    for (const auto& m : scene.materials)
        any |= !m.color_texture.empty() || !m.bump_texture.empty() || !m.normal_texture.empty() || !m.ao_texture.empty() ||
               !m.metallic_roughness_texture.empty();
    if (any) {
        textures_ = OIIO::TextureSystem::create(false);
        textures_->attribute("max_memory_MB", 1024.0f);
        textures_->attribute("automip", 1);
    }
    auto unique = [](const std::string& f) { return f.empty() ? nullptr : OIIO::ustring(f).c_str(); };
    for (const auto& m : scene.materials)
        names_.push_back({unique(m.color_texture), unique(m.bump_texture), unique(m.normal_texture), unique(m.ao_texture),
                          unique(m.metallic_roughness_texture)});
}

Materials::~Materials() {
    if (textures_) OIIO::TextureSystem::destroy(textures_);
}

namespace {

/// Texture lookup at uv with an axis-aligned filter of (du, dv) uv units; image rows run
/// top-down while v runs bottom-up. Returns false when the file cannot be read.
bool lookup(OIIO::TextureSystem* ts, const char* file, const Vec2& uv, float du, float dv, int channels, float* out, float* d_ds = nullptr,
            float* d_dt = nullptr) {
    OIIO::TextureOpt opt;
    opt.swrap = opt.twrap = OIIO::TextureOpt::WrapPeriodic;
    return ts->texture(OIIO::ustring::from_unique(file), opt, uv.x, 1 - uv.y, du, 0, 0, dv, channels, out, d_ds, d_dt);
}

/// A texture's colour as an albedo: NaN and infinities (a broken map) are black, values
/// beyond 1 clamp to 1 (energy conservation), so no texel can make a pixel NaN.
Color albedo_of(const float* rgb) {
    Color c;
    for (int i = 0; i < 3; ++i) c[i] = std::isfinite(rgb[i]) ? std::clamp(rgb[i], 0.0f, 1.0f) : 0.0f;
    return c;
}

bool all_finite(const float* v, int n) {
    return std::all_of(v, v + n, [](float x) { return std::isfinite(x); });
}

}  // namespace

Color Materials::base_colour(uint32_t material, const Vec2& st, float du, float dv) const {
    const Material& m = scene_.materials[material];
    float rgb[3] = {1, 1, 1};
    if (!m.color_texture.empty() && textures_ && lookup(textures_, names_[material].color, st, du, dv, 3, rgb))
        return m.color * albedo_of(rgb);
    return m.color;
}

float Materials::metalness(uint32_t material, const Vec2& st, float du, float dv, float* roughness) const {
    const Material& m = scene_.materials[material];
    if (m.metallic_roughness_texture.empty() || !textures_) return -1;
    float rgb[3] = {0, 1, 1};
    if (!lookup(textures_, names_[material].metallic_roughness, st, du, dv, 3, rgb) || !all_finite(rgb, 3)) rgb[1] = rgb[2] = 1;
    if (roughness) *roughness = std::clamp(m.roughness * rgb[1], 0.01f, 1.0f);
    return std::clamp(m.metallic * rgb[2], 0.0f, 1.0f);
}

Color Materials::albedo(uint32_t material, const Vec2& uv) const {
    const Material& m = scene_.materials[material];
    const Vec2 st = m.uv_transform.apply(uv);
    const Color base = base_colour(material, st, 0, 0);
    // Without a metallic texture the factor is 1 x (1 - t): the base colour itself when opaque.
    if (m.metallic_roughness_texture.empty() || !textures_) return m.diffuse_transmission == 0 ? base : base * (1 - m.diffuse_transmission);
    const float metal = metalness(material, st, 0, 0);
    return base * ((metal > 0 ? 1 - metal : 1.0f) * (1 - m.diffuse_transmission));
}

Color Materials::translucency(uint32_t material, const Vec2& uv) const {
    const Material& m = scene_.materials[material];
    if (!m.is_translucent()) return Color(0);
    const float metal = metalness(material, m.uv_transform.apply(uv), 0, 0);
    return m.diffuse_transmission_color * (m.diffuse_transmission * (metal > 0 ? 1 - metal : 1.0f));
}

float fresnel_dielectric(float cos_i, float eta) {
    cos_i = std::clamp(cos_i, 0.0f, 1.0f);
    const float sin_t2 = (1 - cos_i * cos_i) / (eta * eta);
    if (sin_t2 >= 1) return 1;
    const float cos_t = std::sqrt(1 - sin_t2);
    const float rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    const float rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    return 0.5f * (rs * rs + rp * rp);
}

bool refract(const Vec3& d, const Vec3& n, float eta, Vec3& out) {
    const float cos_i = -dot(d, n);
    const float k = 1 - eta * eta * (1 - cos_i * cos_i);
    if (k < 0) return false;
    out = normalize(d * eta + n * (eta * cos_i - std::sqrt(k)));
    return true;
}

SpecularSplit specular_split(const Material& m, float cos_i, bool entering) {
    SpecularSplit s;
    const float F = m.is_dielectric() ? fresnel_dielectric(cos_i, entering ? m.ior : 1 / m.ior) : 0.0f;
    for (int c = 0; c < 3; ++c) {
        const float rest = (1 - m.mirror[c]) * (1 - F);
        s.reflect[c] = m.mirror[c] + (1 - m.mirror[c]) * F;
        s.transmit[c] = rest * m.transmission[c];
        s.base[c] = rest * (1 - m.transmission[c]);
    }
    return s;
}

Color base_share(const Material& m) { return m.is_specular() ? specular_split(m, 1, true).base : Color(1); }

Color Materials::secondary_albedo(const SurfacePoint& sp) const {
    return albedo(sp.material, sp.uv) * sp.color * base_share(scene_.materials[sp.material]);
}

Color Materials::translucent_share(const SurfacePoint& sp) const {
    return translucency(sp.material, sp.uv) * base_share(scene_.materials[sp.material]);
}

Color Materials::vertex_color(uint32_t object, uint32_t prim, const Vec3& p) const {
    const Object& o = scene_.objects[object];
    const TriangleMesh& mesh = o.visible_mesh();
    return mesh.colors.empty() ? Color(1) : vertex_color_at(mesh, o.to_world(), prim, p);
}

bool triangle_tangents(const TriangleMesh& mesh, uint32_t prim, Vec3& dpdu, Vec3& dpdv, const UvTransform* xf) {
    if (mesh.uvs.empty()) return false;
    const uint32_t i0 = mesh.indices[3 * prim], i1 = mesh.indices[3 * prim + 1], i2 = mesh.indices[3 * prim + 2];
    const Vec3 e1 = mesh.positions[i1] - mesh.positions[i0], e2 = mesh.positions[i2] - mesh.positions[i0];
    const auto uv = [&](uint32_t i) { return xf ? xf->apply(mesh.uvs[i]) : mesh.uvs[i]; };
    const Vec2 u0 = uv(i0), u1 = uv(i1), u2 = uv(i2);
    const Vec2 t1{u1.x - u0.x, u1.y - u0.y};
    const Vec2 t2{u2.x - u0.x, u2.y - u0.y};
    const float det = t1.x * t2.y - t1.y * t2.x;
    if (std::abs(det) < 1e-12f) return false;
    dpdu = (e1 * t2.y - e2 * t1.y) / det;
    dpdv = (e2 * t1.x - e1 * t2.x) / det;
    return true;
}

Vec3 bumped_normal(const Vec3& n, const Vec3& dpdu, const Vec3& dpdv, float dhdu, float dhdv) {
    if (dhdu == 0 && dhdv == 0) return n;
    // d(P + h n)/du x d(P + h n)/dv = (dpdu x dpdv) + dhdu (n x dpdv) - dhdv (n x dpdu) + O(h);
    // divided by a = n.(dpdu x dpdv) it is n plus the tilt, whatever the uv orientation.
    const float a = dot(n, cross(dpdu, dpdv));
    if (std::abs(a) < 1e-20f) return n;
    const Vec3 b = normalize(n + (cross(n, dpdv) * dhdu - cross(n, dpdu) * dhdv) / a);
    return isfinite(b) && dot(b, b) > 0.5f ? b : n;  // a huge slope overflows: keep the normal
}

SurfaceShading Materials::surface(uint32_t material, uint32_t object, uint32_t prim, const Vec3& p, const Vec2& uv, const Vec3& n,
                                  float footprint) const {
    const Material& m = scene_.materials[material];
    SurfaceShading s;
    s.specular = m.specular;
    s.roughness = m.roughness;
    s.normal = n;
    Vec3 dpdu, dpdv;
    const Object& o = scene_.objects[object];
    const Vec2 st = m.uv_transform.apply(uv);
    const bool tangents = triangle_tangents(o.visible_mesh(), prim, dpdu, dpdv, &m.uv_transform);
    if (tangents && o.to_world()) dpdu = o.to_world()->vector(dpdu), dpdv = o.to_world()->vector(dpdv);
    // Filter width in uv: the pixel's footprint over the length of the tangents.
    float du = 0, dv = 0;
    if (tangents) {
        du = footprint / std::max(length(dpdu), 1e-20f);
        dv = footprint / std::max(length(dpdv), 1e-20f);
    }
    s.albedo = base_colour(material, st, du, dv) * vertex_color(object, prim, p);
    float dielectric = 1;  // the share of glTF's metallic-roughness that is not metal
    if (const float metal = metalness(material, st, du, dv, &s.roughness); metal >= 0) {
        s.specular = Color(0.04f) * (1 - metal) + s.albedo * metal;
        dielectric = 1 - metal;
    }
    // KHR_materials_diffuse_transmission: the transmitted share leaves the reflected one.
    s.albedo = s.albedo * (dielectric * (1 - m.diffuse_transmission));
    if (m.is_translucent()) s.translucency = m.diffuse_transmission_color * (m.diffuse_transmission * dielectric);
    if (!m.ao_texture.empty() && textures_) {
        float ao = 1;
        if (lookup(textures_, names_[material].ao, st, du, dv, 1, &ao) && std::isfinite(ao)) s.occlusion = std::clamp(ao, 0.0f, 1.0f);
    }
    if (!m.has_bump() || !tangents || !textures_) return s;
    if (!m.bump_texture.empty()) {
        float h = 0, dh_ds = 0, dh_dt = 0;
        if (lookup(textures_, names_[material].bump, st, du, dv, 1, &h, &dh_ds, &dh_dt) && std::isfinite(dh_ds) && std::isfinite(dh_dt))
            s.normal = bumped_normal(n, dpdu, dpdv, m.bump_strength * dh_ds, -m.bump_strength * dh_dt);  // t = 1 - v
        return s;
    }
    float rgb[3] = {0.5f, 0.5f, 1};
    if (!lookup(textures_, names_[material].normal, st, du, dv, 3, rgb) || !all_finite(rgb, 3)) return s;
    // Tangent frame from dP/du (Gram-Schmidt against n); the bitangent follows dP/dv's side.
    Vec3 t = dpdu - n * dot(n, dpdu);
    if (dot(t, t) <= 0) return s;
    t = normalize(t);
    Vec3 b = cross(n, t);
    if (dot(b, dpdv) < 0) b = -b;
    Vec3 local(m.bump_strength * (2 * rgb[0] - 1), m.bump_strength * (2 * rgb[1] - 1), 2 * rgb[2] - 1);
    const Vec3 nn = normalize(t * local.x + b * local.y + n * std::max(local.z, 0.0f));
    if (isfinite(nn) && dot(nn, nn) > 0.5f) s.normal = nn;
    return s;
}

}  // namespace bounce
