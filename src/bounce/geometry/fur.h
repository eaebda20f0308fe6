// Fur and grass: strands grown deterministically on a growing surface (docs/fur.md). Each strand
// is a polyline of flat linear curve segments (Embree ribbons facing the ray) and keeps its root
// position, root normal and root uv on the growing surface: where its cache lookups happen.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "bounce/core/math.h"
#include "bounce/geometry/mesh.h"

namespace bounce {

/// A scalar map over the growing surface's uv square (density or length), values in [0, 1].
struct UvMap {
    int width = 0, height = 0;
    std::vector<float> values;  ///< row 0 at v = 1 (image order)
    float at(const Vec2& uv) const;
};

/// Which rays see an object or its fur (scene file: "visible_to").
struct RayVisibility {
    bool camera = true;       ///< primary visibility
    bool shadows = true;      ///< shadow rays of direct light (and of the radiosity bake)
    bool indirect = true;     ///< gather rays (the bounce light and AO)
    bool reflections = true;  ///< rays of mirrors and glass (reflection and refraction)
};

/// Where a hair fragment's indirect light is looked up (and, for brute force, gathered).
enum class FurIndirectAt : uint8_t { Root, Fragment };

/// An object's "fur" block: how strands grow and how they are shaded.
struct FurParams {
    uint64_t count = 0;                             ///< strands grown (before the density map thins them)
    float length = 0.1f;                            ///< world units
    float length_variation = 0.2f;                  ///< each strand's length is length x (1 +- this), uniform
    float width_root = 0.004f, width_tip = 0.001f;  ///< world units
    int segments = 4;                               ///< linear segments per strand
    float curl = 0;                                 ///< helix radius as a fraction of the length
    float curl_turns = 2;                           ///< helix turns over the strand
    float gravity = 0;                              ///< bend towards -Y: tip drop as a fraction of the length (0..1)
    float clump = 0;                                ///< how far tips are drawn to their clump's guide strand (0..1)
    float clump_size = 0.05f;                       ///< clumps: strands whose roots share a cell of this size (world units)
    float lean = 0.15f;                             ///< random tilt of the root direction from the normal (radians)
    uint64_t seed = 1;
    Color color_root{0.3f}, color_tip{0.6f};  ///< diffuse albedo, root to tip
    float specular = 0.04f;                   ///< Kajiya-Kay specular strength
    float specular_exponent = 40;             ///< Kajiya-Kay specular exponent
    float falloff_root = 0.35f;               ///< self-shadowing f(v) at the root (f = 1 at the tip)
    float falloff_exponent = 1;               ///< f(v) = root + (1 - root) v^exponent
    /// Which rays see the strands: the camera and shadow rays, not gathers nor mirrors unless
    /// asked ("cast_indirect" and "cast_shadows" are the older names of indirect and shadows).
    RayVisibility visible_to{true, true, false, false};
    FurIndirectAt indirect_at = FurIndirectAt::Root;
    std::shared_ptr<const UvMap> density_map, length_map;

    /// Self-shadowing falloff at v (0 = root, 1 = tip) multiplying cached irradiance and AO.
    float falloff(float v) const;
    /// Albedo at v.
    Color albedo(float v) const { return color_root + (color_tip - color_root) * v; }
    /// Bytes a fur of `strands` strands takes (vertices, indices, roots) plus Embree's BVH
    /// over its segments (estimated at 64 bytes a segment).
    size_t memory_bytes(uint64_t strands) const;
};

/// The strands of one object.
struct Fur {
    FurParams params;
    int segments = 0;                     ///< per strand
    std::vector<float> vertices;          ///< (x, y, z, radius) per control point, segments+1 per strand
    std::vector<uint32_t> segment_first;  ///< per segment: index of its first control point
    std::vector<Vec3> root_p, root_n;     ///< per strand, on the growing surface
    std::vector<Vec2> root_uv;
    /// Per strand, where its root lies on the growing surface: a triangle and barycentrics
    /// (Embree's u, v). A pose of the same surface carries the strand there (carry_fur).
    std::vector<uint32_t> root_tri;
    std::vector<Vec2> root_bary;
    double seconds = 0;  ///< generation time

    size_t strand_count() const { return root_p.size(); }
    size_t segment_count() const { return segment_first.size(); }
    uint32_t strand_of(uint32_t segment) const { return segment / static_cast<uint32_t>(segments); }
    /// Position along the strand (0 root, 1 tip) at parameter u of `segment`.
    float v_of(uint32_t segment, float u) const {
        return (static_cast<float>(segment % static_cast<uint32_t>(segments)) + u) / static_cast<float>(segments);
    }
    /// Unit tangent of `segment` (root to tip).
    Vec3 tangent(uint32_t segment) const;
    /// Largest strand width.
    float max_width() const { return std::max(params.width_root, params.width_tip); }
    size_t memory_bytes() const;
};

/// Grows `params.count` strands on `surface` (area-weighted, thinned by the density map),
/// each a pure function of (seed, strand index): the same seed gives the same fur.
Fur grow_fur(const TriangleMesh& surface, const FurParams& params);

/// Whether `to` is the surface `from` in another pose: the same triangles over as many vertices.
bool same_triangles(const TriangleMesh& from, const TriangleMesh& to);

/// Carries the strands of `fur`, grown on `from`, to `to` (same_triangles must hold): each root
/// stays at its triangle and barycentrics, and the strand turns with the surface's frame there
/// (the root's normal and its triangle's first edge), keeping its shape and length. A groom then
/// follows a skin or a moving object strand for strand, where growing it again on each pose would
/// place strands by that pose's areas and clump them by cells the pose moved through.
void carry_fur(Fur& fur, const TriangleMesh& from, const TriangleMesh& to);
/// The control points (as Fur::vertices) that carry_fur would give `fur`, leaving it as it is:
/// its strands at shutter open and close.
std::vector<float> carried_vertices(const Fur& fur, const TriangleMesh& from, const TriangleMesh& to);

/// The Kajiya-Kay hair reflectance for direct light arriving from unit `wi` at a strand of
/// unit tangent `t`, seen from unit `wo`, per unit of (radiance x solid angle): the diffuse
/// lobe albedo sin(t, wi) (2 / pi^2) and the specular cone specular cos^e. The diffuse
/// normalisation makes a strand standing on a surface under a uniform sky reflect what the
/// surface itself does (albedo E / pi).
Color kajiya_kay(const Vec3& t, const Vec3& wi, const Vec3& wo, const Color& albedo, float specular, float exponent);

/// Radiance a strand of tangent `t` reflects towards `wo` under cached irradiance `e` (about
/// the growing surface's normal `n`) whose light arrives about unit direction `d`. Diffuse: the
/// light read as a uniform hemisphere about d, under which a Kajiya-Kay fibre reflects exactly
/// albedo E / pi whatever its orientation (sin(t, w) is even in w, so its integral over any
/// hemisphere is half the sphere's). Specular: the pair read as surfaces read it (shade/brdf.h),
/// all of the light from d with radiance x solid angle E / (n . d).
Color hair_indirect(const Vec3& t, const Vec3& d, const Vec3& n, const Vec3& wo, const Color& e, const Color& albedo, float specular,
                    float exponent);

}  // namespace bounce
