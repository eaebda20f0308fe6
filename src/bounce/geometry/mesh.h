// Triangle meshes and the tessellations bounce builds from them: the coarse one that secondary
// rays trace and the fine one that primary visibility sees.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "bounce/core/math.h"

namespace bounce {

struct TriangleMesh {
    std::vector<Vec3> positions;
    std::vector<Vec3> normals;  ///< per vertex shading normals; empty = use geometric normals
    std::vector<Vec2> uvs;      ///< per vertex; empty = none
    /// Per vertex, multiplying the albedo (glTF's COLOR_0), each in [0, 1]; empty = none.
    std::vector<Color> colors;
    std::vector<uint32_t> indices;         ///< 3 per triangle
    std::vector<uint32_t> face_materials;  ///< per triangle index into Scene::materials
    /// Per vertex, the surface before displacement (the limit surface of a subdivision
    /// surface): where cache records live. Empty = the mesh is not displaced.
    std::vector<Vec3> base_positions;
    std::vector<Vec3> base_normals;
    bool displaced() const { return !base_positions.empty(); }

    size_t triangle_count() const { return indices.size() / 3; }
    /// Area of triangle t.
    float triangle_area(size_t t) const;
    /// Sum of the triangles' areas.
    double area() const;
    Bounds bounds() const;
    /// Applies a transform to positions and normals.
    void transform(const Transform& t);
    /// Appends another mesh (indices re-based); neither may be displaced.
    void append(const TriangleMesh& other);
};

/// Splits every triangle into four at its edge midpoints, `levels` times. Positions stay on
/// the input surface (linear), normals and uvs are interpolated.
TriangleMesh subdivide_linear(const TriangleMesh& mesh, int levels);

/// Icosahedron subdivided `level` times with vertices on the sphere; exact sphere normals.
/// Level 0 has 20 triangles; each level multiplies by 4.
TriangleMesh make_icosphere(const Vec3& center, float radius, int level, uint32_t material);

/// A planar quad from four corners in order (two triangles), uvs (0,0) (1,0) (1,1) (0,1).
TriangleMesh make_quad(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, uint32_t material);

}  // namespace bounce

namespace bounce {

/// A point on a triangle, with everything shading needs.
struct SurfacePoint {
    Vec3 p;
    Vec3 n;   ///< shading normal (interpolated), unit
    Vec3 ng;  ///< geometric normal, unit, same side as n
    Vec2 uv;
    Color color{1};  ///< the vertex colours there (1 without)
    uint32_t material = 0;
};

/// The vertex colours of triangle `prim` at barycentrics (u, v), written so that equal colours
/// interpolate to exactly themselves (1 when the mesh has none).
Color vertex_color(const TriangleMesh& mesh, uint32_t prim, float u, float v);
/// At point `p` (world space; `to_world` places the mesh, null = in place), projected onto the
/// triangle's plane and clamped to it: for what keeps a point, not barycentrics (the deep buffer's fragments).
Color vertex_color_at(const TriangleMesh& mesh, const Transform* to_world, uint32_t prim, const Vec3& p);

/// Evaluates triangle `prim` of `mesh` at barycentrics (u, v) (Embree's convention:
/// p = (1-u-v) v0 + u v1 + v v2).
SurfacePoint surface_point(const TriangleMesh& mesh, uint32_t prim, float u, float v);
/// The same for a mesh placed by `to_world` (an instance's shared prototype; null = in place):
/// the triangle's vertices and normals are moved as TriangleMesh::transform moves them, then
/// interpolated, so a placed mesh's points equal those of the same mesh transformed, bit for bit.
SurfacePoint surface_point(const TriangleMesh& mesh, const Transform* to_world, uint32_t prim, float u, float v);
/// Triangle `prim`'s three vertices, placed by `to_world` (null = in place).
std::array<Vec3, 3> triangle_vertices(const TriangleMesh& mesh, const Transform* to_world, uint32_t prim);
/// Triangle `prim`'s unit normal by its winding (surface_point's ng may face the other way):
/// what needs only the plane reads three positions, not the normals and uvs.
Vec3 face_normal(const TriangleMesh& mesh, uint32_t prim);
/// The same for a mesh placed by `to_world` (null = in place).
Vec3 face_normal(const TriangleMesh& mesh, const Transform* to_world, uint32_t prim);

/// The un-displaced position and (unit, not oriented) normal at barycentrics (u, v) of a
/// displaced mesh's triangle `prim` (mesh.displaced() must hold).
std::pair<Vec3, Vec3> base_point(const TriangleMesh& mesh, uint32_t prim, float u, float v);

}  // namespace bounce
