// Dicing: subdivision surfaces (OpenSubdiv) turned into the two tessellations bounce traces,
// optionally displaced. The fine one (primary visibility) is diced to about `shading_rate`
// pixels per micropolygon edge from the camera; the coarse one (every secondary ray) at a
// fixed level. Both carry the un-displaced limit surface per vertex (TriangleMesh::base_*),
// where cache records live (docs/displacement.md).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "bounce/geometry/mesh.h"

namespace bounce {

enum class SubdivScheme { CatmullClark, Loop };
enum class SubdivBoundary { EdgeOnly, EdgeAndCorner };

/// A polygon control mesh: vertices welded by position (so uv seams do not cut the surface),
/// uvs per face corner (face-varying).
struct ControlMesh {
    std::string source;  ///< file, for error messages
    std::vector<Vec3> positions;
    std::vector<int> face_sizes;     ///< corners per face (>= 3)
    std::vector<int> face_vertices;  ///< corner -> vertex
    std::vector<Vec2> uvs;           ///< distinct uv values
    std::vector<int> face_uvs;       ///< corner -> uv value (empty = no uvs)
    std::vector<uint32_t> face_materials;
    /// The file had vertex colours (glTF's COLOR_0), which subdivision does not carry.
    bool dropped_vertex_colors = false;
    size_t face_count() const { return face_sizes.size(); }
};

class DisplacementMap;

/// Scalar displacement along the limit normal: scale * (map(uv) - midpoint).
struct Displacement {
    std::shared_ptr<const DisplacementMap> map;
    float scale = 0;
    float midpoint = 0.5f;
    bool active() const { return map && scale != 0; }
    /// How far the point with texture coordinate `uv` moves along its normal (active() only).
    float offset(const Vec2& uv) const;
};

struct SubdivSurface {
    ControlMesh control;
    SubdivScheme scheme = SubdivScheme::CatmullClark;
    SubdivBoundary boundary = SubdivBoundary::EdgeAndCorner;
    Displacement displacement;
};

/// Most faces that may meet at one control vertex (check_control_mesh).
inline constexpr int kMaxValence = 256;

/// Throws InputError (naming control.source) for a control mesh OpenSubdiv cannot refine as
/// a manifold surface: an edge shared by more than two faces, faces that disagree on an
/// edge's direction, a Loop mesh with non-triangles, out-of-range indices, a position that is
/// not finite, or more than kMaxValence faces round one vertex.
void check_control_mesh(const ControlMesh& control, SubdivScheme scheme);

/// The surface refined `level` times (uniformly) and split into triangles: vertices on the
/// limit surface, displaced along the limit normal when the surface has a displacement;
/// base_positions/base_normals hold the un-displaced limit surface, normals the displaced
/// surface's (averaged over the diced faces around each vertex).
TriangleMesh dice(const SubdivSurface& surface, int level);

/// The surface diced per control face (OpenSubdiv's Bfr): each control edge is split into
/// `edge_rate(a, b)` segments (a, b: its control end points; at least 1), both faces of an edge
/// use its rate and share its points, so faces of different rates meet without cracks; each
/// face's interior follows its edges. Otherwise as dice(): vertices on the limit surface,
/// displaced once per point along the limit normal, base_* the un-displaced surface, normals
/// the displaced surface's. Vertices are per face (positions shared exactly across edges).
TriangleMesh dice_adaptive(const SubdivSurface& surface, const std::function<int(const Vec3&, const Vec3&)>& edge_rate);

/// The control mesh refined `level` times (uniformly, not pushed to the limit): the same
/// limit surface on a denser cage, all quads for Catmull-Clark from level 1 (uvs linear, as
/// dice's). For ray sides that take cages of quads only (bench/ray_side.cpp).
ControlMesh refine_cage(const SubdivSurface& surface, int level);

/// The refinement level at which the fine tessellation's edges are about `shading_rate`
/// pixels: log2 of the median of the control edges' projected lengths, rounded
/// (`pixels_per_unit(p)`: pixels per world unit at p, 0 behind the camera), in [min, max].
int dicing_level(const ControlMesh& control, const std::function<float(const Vec3&)>& pixels_per_unit, float shading_rate, int min_level,
                 int max_level);

}  // namespace bounce
