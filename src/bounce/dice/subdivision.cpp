#include "bounce/dice/subdivision.h"

#include <fmt/format.h>
#include <opensubdiv/bfr/refinerSurfaceFactory.h>
#include <opensubdiv/bfr/surface.h>
#include <opensubdiv/bfr/tessellation.h>
#include <opensubdiv/far/primvarRefiner.h>
#include <opensubdiv/far/topologyDescriptor.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <unordered_map>

#include "bounce/core/error.h"
#include "bounce/dice/displacement.h"

namespace bounce {

namespace {

namespace Bfr = OpenSubdiv::Bfr;
namespace Far = OpenSubdiv::Far;
namespace Sdc = OpenSubdiv::Sdc;

/// Primvar types for Far's refiners (Clear + AddWithWeight is all they need).
struct P3 {
    Vec3 v{0};
    void Clear(void* = nullptr) { v = Vec3(0); }
    void AddWithWeight(const P3& s, float w) { v += s.v * w; }
};
struct P2 {
    Vec2 v{};
    void Clear(void* = nullptr) { v = Vec2{}; }
    void AddWithWeight(const P2& s, float w) { v.x += s.v.x * w, v.y += s.v.y * w; }
};

std::unique_ptr<Far::TopologyRefiner> make_refiner(const SubdivSurface& s) {
    using Factory = Far::TopologyRefinerFactory<Far::TopologyDescriptor>;
    const ControlMesh& c = s.control;
    Far::TopologyDescriptor desc;
    desc.numVertices = static_cast<int>(c.positions.size());
    desc.numFaces = static_cast<int>(c.face_count());
    desc.numVertsPerFace = c.face_sizes.data();
    desc.vertIndicesPerFace = c.face_vertices.data();
    Far::TopologyDescriptor::FVarChannel uv;
    if (!c.face_uvs.empty()) {
        uv.numValues = static_cast<int>(c.uvs.size());
        uv.valueIndices = c.face_uvs.data();
        desc.numFVarChannels = 1;
        desc.fvarChannels = &uv;
    }
    Sdc::Options options;
    options.SetVtxBoundaryInterpolation(s.boundary == SubdivBoundary::EdgeOnly ? Sdc::Options::VTX_BOUNDARY_EDGE_ONLY
                                                                               : Sdc::Options::VTX_BOUNDARY_EDGE_AND_CORNER);
    // uvs stay smooth inside each uv chart and pinned at chart corners, as modelling tools do.
    options.SetFVarLinearInterpolation(Sdc::Options::FVAR_LINEAR_ALL);
    const Sdc::SchemeType type = s.scheme == SubdivScheme::Loop ? Sdc::SCHEME_LOOP : Sdc::SCHEME_CATMARK;
    std::unique_ptr<Far::TopologyRefiner> r(Factory::Create(desc, Factory::Options(type, options)));
    if (!r) throw InputError(c.source, "", "OpenSubdiv cannot build a subdivision surface from this mesh");
    return r;
}

/// The un-displaced normal from the limit tangents' cross product `n` (|du|^2 + |dv|^2 =
/// `tangents2`), oriented by `around` (the diced faces' normals at the point), which stands in
/// where the cross product degenerates (extraordinary vertices).
Vec3 limit_normal(Vec3 n, float tangents2, const Vec3& around) {
    if (!(length(n) > 1e-12f * tangents2))
        n = around;
    else if (dot(n, around) < 0)
        n = -n;
    return dot(n, n) > 0 ? normalize(n) : Vec3(0, 0, 1);
}

/// Positions and uvs refined level by level to `level` (the refiner already refined).
void refine_primvars(const Far::TopologyRefiner& refiner, int level, std::vector<P3>& pts, std::vector<P2>& uvs) {
    const Far::PrimvarRefiner primvar(refiner);
    for (int l = 1; l <= level; ++l) {
        std::vector<P3> next(static_cast<size_t>(refiner.GetLevel(l).GetNumVertices()));
        primvar.Interpolate(l, pts, next);
        pts.swap(next);
        if (!uvs.empty()) {
            std::vector<P2> nuv(static_cast<size_t>(refiner.GetLevel(l).GetNumFVarValues(0)));
            primvar.InterpolateFaceVarying(l, uvs, nuv, 0);
            uvs.swap(nuv);
        }
    }
}

/// The control mesh's positions and uvs as primvars.
void control_primvars(const ControlMesh& c, std::vector<P3>& pts, std::vector<P2>& uvs) {
    pts.resize(c.positions.size());
    for (size_t i = 0; i < pts.size(); ++i) pts[i].v = c.positions[i];
    uvs.resize(c.face_uvs.empty() ? 0 : c.uvs.size());
    for (size_t i = 0; i < uvs.size(); ++i) uvs[i].v = c.uvs[i];
}

}  // namespace

float Displacement::offset(const Vec2& uv) const { return scale * (map->height(uv) - midpoint); }

void check_control_mesh(const ControlMesh& c, SubdivScheme scheme) {
    const auto nv = static_cast<int>(c.positions.size());
    if (c.face_count() == 0) throw InputError(c.source, "", "control mesh has no faces");
    for (size_t v = 0; v < c.positions.size(); ++v)
        if (!isfinite(c.positions[v])) throw InputError(c.source, fmt::format("vertex {}", v), "position is not finite");
    // OpenSubdiv's patch for an irregular vertex costs far more than linear in its valence
    // (measured on a fan at 32x32: 256 faces round one vertex 0.5 s, 512 1.0 s, 1000 3.7 s,
    // 2000 275 s): refuse it up front.
    std::vector<int> valence(c.positions.size(), 0);
    for (const int v : c.face_vertices)
        if (v >= 0 && v < nv && ++valence[static_cast<size_t>(v)] > kMaxValence)
            throw InputError(c.source, fmt::format("vertex {}", v),
                             fmt::format("more than {} faces meet at this vertex (subdividing it would take minutes); "
                                         "split the fan",
                                         kMaxValence));
    // Directed edge -> face that uses it; an undirected edge may appear once each way.
    std::unordered_map<uint64_t, size_t> directed;
    directed.reserve(c.face_vertices.size());
    size_t corner = 0;
    for (size_t f = 0; f < c.face_count(); ++f) {
        const int n = c.face_sizes[f];
        if (n < 3 || (scheme == SubdivScheme::Loop && n != 3))
            throw InputError(c.source, fmt::format("face {}", f),
                             scheme == SubdivScheme::Loop ? "Loop subdivision needs triangles" : "face has fewer than 3 corners");
        for (int k = 0; k < n; ++k) {
            const int a = c.face_vertices[corner + k], b = c.face_vertices[corner + (k + 1) % n];
            if (a < 0 || a >= nv) throw InputError(c.source, fmt::format("face {}", f), "vertex index out of range");
            if (a == b) throw InputError(c.source, fmt::format("face {}", f), "face repeats a vertex (degenerate)");
            const uint64_t key = (static_cast<uint64_t>(a) << 32) | static_cast<uint32_t>(b);
            auto [it, fresh] = directed.emplace(key, f);
            if (!fresh)
                throw InputError(c.source, fmt::format("face {}", f),
                                 fmt::format("edge {}-{} is also used in the same direction by face {}: the mesh is "
                                             "non-manifold or its faces disagree on orientation",
                                             a, b, it->second));
        }
        corner += static_cast<size_t>(n);
    }
}

int dicing_level(const ControlMesh& c, const std::function<float(const Vec3&)>& pixels_per_unit, float shading_rate, int min_level,
                 int max_level) {
    std::vector<float> px;
    size_t corner = 0;
    for (size_t f = 0; f < c.face_count(); ++f) {
        const int n = c.face_sizes[f];
        for (int k = 0; k < n; ++k) {
            const Vec3 &a = c.positions[static_cast<size_t>(c.face_vertices[corner + k])],
                       &b = c.positions[static_cast<size_t>(c.face_vertices[corner + (k + 1) % n])];
            const float s = pixels_per_unit((a + b) * 0.5f);
            if (s > 0) px.push_back(length(b - a) * s);
        }
        corner += static_cast<size_t>(n);
    }
    if (px.empty()) return min_level;
    // The median edge, rounded in log2: diced edges of 0.7-1.4 x shading_rate, about two
    // micropolygons per pixel at rate 1 (the 90th percentile with a ceiling gave 38 on the ogre).
    auto at = px.begin() + static_cast<std::ptrdiff_t>(px.size() / 2);
    std::nth_element(px.begin(), at, px.end());
    const float levels = std::log2(std::max(*at / shading_rate, 1.0f));
    return std::clamp(static_cast<int>(std::lround(levels)), min_level, max_level);
}

namespace {

/// A point shared between the faces of an adaptive dicing.
struct DicedPoint {
    Vec3 p, n;        // un-displaced limit position and normal (the derivatives' cross product, then limit_normal)
    float tangents2;  // |du|^2 + |dv|^2 (limit_normal's degeneracy scale)
    Vec2 uv;          // where the displacement is read (the first face's uv)
};

/// Each control edge's segment count (at least 1).
std::vector<int> edge_rates(const Far::TopologyLevel& base, const ControlMesh& c,
                            const std::function<int(const Vec3&, const Vec3&)>& edge_rate) {
    std::vector<int> rates(static_cast<size_t>(base.GetNumEdges()));
    for (int e = 0; e < base.GetNumEdges(); ++e) {
        const auto ev = base.GetEdgeVertices(e);
        rates[static_cast<size_t>(e)] =
            std::max(1, edge_rate(c.positions[static_cast<size_t>(ev[0])], c.positions[static_cast<size_t>(ev[1])]));
    }
    return rates;
}

/// A face's tessellation's triangles, its vertices numbered from `first`.
void append_facets(const Bfr::Tessellation& tess, uint32_t first, uint32_t material, std::vector<int>& facets, TriangleMesh& m) {
    facets.resize(3 * static_cast<size_t>(tess.GetNumFacets()));
    tess.GetFacets(facets.data());
    for (size_t t = 0; t < facets.size(); t += 3) {
        m.indices.insert(m.indices.end(), {first + static_cast<uint32_t>(facets[t]), first + static_cast<uint32_t>(facets[t + 1]),
                                           first + static_cast<uint32_t>(facets[t + 2])});
        m.face_materials.push_back(material);
    }
}

/// The mesh's positions and normals from its shared points (`out_point`: each output vertex's).
void place_points(const SubdivSurface& s, std::vector<DicedPoint>& pts, const std::vector<int>& out_point, TriangleMesh& m) {
    // Normals per shared point: the facets around it orient the derivatives' cross product and
    // stand in where it degenerates (limit_normal, as dice does); then displace once per point.
    auto facet_sums = [&](auto position) {
        std::vector<Vec3> sums(pts.size(), Vec3(0));
        for (size_t t = 0; t < m.indices.size(); t += 3) {
            const int a = out_point[m.indices[t]], b = out_point[m.indices[t + 1]], d = out_point[m.indices[t + 2]];
            const Vec3 fn = cross(position(b) - position(a), position(d) - position(a));
            for (int q : {a, b, d}) sums[static_cast<size_t>(q)] += fn;
        }
        return sums;
    };
    const std::vector<Vec3> around = facet_sums([&](int i) { return pts[static_cast<size_t>(i)].p; });
    std::vector<Vec3> disp(pts.size());
    for (size_t i = 0; i < pts.size(); ++i) {
        DicedPoint& q = pts[i];
        q.n = limit_normal(q.n, q.tangents2, around[i]);
        disp[i] = s.displacement.active() ? q.p + q.n * s.displacement.offset(q.uv) : q.p;
    }
    std::vector<Vec3> normals(pts.size());
    if (s.displacement.active()) {
        normals = facet_sums([&](int i) { return disp[static_cast<size_t>(i)]; });
        for (size_t i = 0; i < pts.size(); ++i) normals[i] = dot(normals[i], normals[i]) > 0 ? normalize(normals[i]) : pts[i].n;
    } else {
        for (size_t i = 0; i < pts.size(); ++i) normals[i] = pts[i].n;
    }
    for (int q : out_point) {
        const auto i = static_cast<size_t>(q);
        m.positions.push_back(disp[i]), m.normals.push_back(normals[i]);
        m.base_positions.push_back(pts[i].p), m.base_normals.push_back(pts[i].n);
    }
}

}  // namespace

TriangleMesh dice_adaptive(const SubdivSurface& s, const std::function<int(const Vec3&, const Vec3&)>& edge_rate) {
    const ControlMesh& c = s.control;
    check_control_mesh(c, s.scheme);
    auto refiner = make_refiner(s);  // the base level is all Bfr needs
    const Far::TopologyLevel& base = refiner->GetLevel(0);
    const Bfr::RefinerSurfaceFactory<> factory(*refiner, Bfr::SurfaceFactory::Options().SetDefaultFVarID(0));
    const bool has_uv = !c.face_uvs.empty();
    const std::vector<int> rates = edge_rates(base, c, edge_rate);

    // Points shared between faces: one per control vertex, rate - 1 per control edge (in the
    // edge's own direction), and each face's interior points.
    std::vector<DicedPoint> pts;
    std::vector<int> vertex_point(static_cast<size_t>(base.GetNumVertices()), -1), edge_point(rates.size(), -1);
    std::vector<int> out_point;  // per output vertex: its shared point
    TriangleMesh m;
    Bfr::Surface<float> surface, uv_surface;
    std::vector<float> coords, patch, uv_patch;
    std::vector<int> facets, local;
    const Bfr::Tessellation::Options options;
    for (int f = 0; f < base.GetNumFaces(); ++f) {
        if (!factory.InitVertexSurface(f, &surface)) continue;  // a hole
        if (has_uv && !factory.InitFaceVaryingSurface(f, &uv_surface)) continue;
        const auto fv = base.GetFaceVertices(f), fe = base.GetFaceEdges(f);
        std::vector<int> r(static_cast<size_t>(fv.size()));
        for (int i = 0; i < fv.size(); ++i) r[static_cast<size_t>(i)] = rates[static_cast<size_t>(fe[i])];
        const Bfr::Tessellation tess(surface.GetParameterization(), fv.size(), r.data(), options);
        const int n = tess.GetNumCoords();
        coords.resize(2 * static_cast<size_t>(n));
        tess.GetCoords(coords.data());
        patch.resize(3 * static_cast<size_t>(surface.GetNumPatchPoints()));
        surface.PreparePatchPoints(&c.positions[0].x, 3, patch.data(), 3);
        if (has_uv) {
            uv_patch.resize(2 * static_cast<size_t>(uv_surface.GetNumPatchPoints()));
            uv_surface.PreparePatchPoints(&c.uvs[0].x, 2, uv_patch.data(), 2);
        }
        auto uv_at = [&](int k) {
            Vec2 t{};
            if (has_uv) uv_surface.Evaluate(&coords[2 * static_cast<size_t>(k)], uv_patch.data(), 2, &t.x);
            return t;
        };
        auto make_point = [&](int k) {
            Vec3 p, du, dv;
            surface.Evaluate(&coords[2 * static_cast<size_t>(k)], patch.data(), 3, &p.x, &du.x, &dv.x);
            pts.push_back({p, cross(du, dv), dot(du, du) + dot(dv, dv), uv_at(k)});
            return static_cast<int>(pts.size() - 1);
        };
        // Boundary coordinates come first, around the face: vertex i, then edge i's points.
        local.assign(static_cast<size_t>(n), -1);
        int b = 0;
        for (int i = 0; i < fv.size(); ++i) {
            int& vp = vertex_point[static_cast<size_t>(fv[i])];
            if (vp < 0) vp = make_point(b);
            local[static_cast<size_t>(b++)] = vp;
            const int k = r[static_cast<size_t>(i)] - 1;
            if (k <= 0) continue;
            const bool forward = base.GetEdgeVertices(fe[i])[0] == fv[i];
            int& ep = edge_point[static_cast<size_t>(fe[i])];
            if (ep < 0) {
                ep = static_cast<int>(pts.size());
                for (int j = 0; j < k; ++j) make_point(b + (forward ? j : k - 1 - j));
            }
            for (int j = 0; j < k; ++j) local[static_cast<size_t>(b + j)] = ep + (forward ? j : k - 1 - j);
            b += k;
        }
        for (; b < n; ++b) local[static_cast<size_t>(b)] = make_point(b);
        // This face's vertices (its own uvs: a uv seam keeps both sides' values).
        const auto first = static_cast<uint32_t>(m.uvs.size());
        for (int k = 0; k < n; ++k) {
            out_point.push_back(local[static_cast<size_t>(k)]);
            m.uvs.push_back(uv_at(k));
        }
        const uint32_t material = f < static_cast<int>(c.face_materials.size()) ? c.face_materials[static_cast<size_t>(f)] : 0;
        append_facets(tess, first, material, facets, m);
    }

    place_points(s, pts, out_point, m);
    if (!has_uv) m.uvs.clear();
    return m;
}

ControlMesh refine_cage(const SubdivSurface& s, int level) {
    check_control_mesh(s.control, s.scheme);
    auto refiner = make_refiner(s);
    refiner->RefineUniform(Far::TopologyRefiner::UniformOptions(level));
    std::vector<P3> pts;
    std::vector<P2> uvs;
    control_primvars(s.control, pts, uvs);
    refine_primvars(*refiner, level, pts, uvs);
    const Far::TopologyLevel& last = refiner->GetLevel(level);
    ControlMesh out;
    out.source = s.control.source;
    for (const P3& p : pts) out.positions.push_back(p.v);
    for (const P2& t : uvs) out.uvs.push_back(t.v);
    for (int f = 0; f < last.GetNumFaces(); ++f) {
        const auto fv = last.GetFaceVertices(f);
        out.face_sizes.push_back(fv.size());
        for (int k = 0; k < fv.size(); ++k) out.face_vertices.push_back(fv[k]);
        if (!uvs.empty())
            for (int v : last.GetFaceFVarValues(f, 0)) out.face_uvs.push_back(v);
        out.face_materials.push_back(0);
    }
    return out;
}

namespace {

/// Per vertex of `last`, the sum of its faces' normals (Newell: twice the area, along the
/// normal), for vertex positions `pos(i)`.
template <class Position>
std::vector<Vec3> vertex_normal_sums(const Far::TopologyLevel& last, const Position& pos) {
    std::vector<Vec3> sums(static_cast<size_t>(last.GetNumVertices()), Vec3(0));
    for (int f = 0; f < last.GetNumFaces(); ++f) {
        const auto fv = last.GetFaceVertices(f);
        Vec3 n(0);
        for (int k = 0; k < fv.size(); ++k) n += cross(pos(fv[k]), pos(fv[(k + 1) % fv.size()]));
        for (int k = 0; k < fv.size(); ++k) sums[static_cast<size_t>(fv[k])] += n;
    }
    return sums;
}

/// Each face of refinement level `level` with its control face's material.
std::vector<uint32_t> diced_materials(const ControlMesh& c, const Far::TopologyRefiner& refiner, int level) {
    std::vector<uint32_t> mat(c.face_materials.begin(), c.face_materials.end());
    if (mat.size() != c.face_count()) mat.assign(c.face_count(), 0);
    for (int l = 1; l <= level; ++l) {
        const Far::TopologyLevel& tl = refiner.GetLevel(l);
        std::vector<uint32_t> child(static_cast<size_t>(tl.GetNumFaces()));
        for (int f = 0; f < tl.GetNumFaces(); ++f) child[static_cast<size_t>(f)] = mat[static_cast<size_t>(tl.GetFaceParentFace(f))];
        mat.swap(child);
    }
    return mat;
}

}  // namespace

TriangleMesh dice(const SubdivSurface& s, int level) {
    const ControlMesh& c = s.control;
    check_control_mesh(c, s.scheme);
    auto refiner = make_refiner(s);
    Far::TopologyRefiner::UniformOptions uo(level);
    uo.fullTopologyInLastLevel = true;  // the limit masks need the last level's edges
    refiner->RefineUniform(uo);
    const Far::PrimvarRefiner primvar(*refiner);

    // Positions (and uvs) level by level, then the last level's points pushed to the limit.
    std::vector<P3> pts;
    std::vector<P2> uvs;
    control_primvars(c, pts, uvs);
    const bool has_uv = !uvs.empty();
    refine_primvars(*refiner, level, pts, uvs);
    const Far::TopologyLevel& last = refiner->GetLevel(level);
    const auto nv = static_cast<size_t>(last.GetNumVertices());
    std::vector<P3> limit(nv), du(nv), dv(nv);
    primvar.Limit(pts, limit, du, dv);

    const int nf = last.GetNumFaces();
    const auto normal_sums = [&](const auto& pos) { return vertex_normal_sums(last, pos); };
    // The limit mesh's face normals orient the limit tangents' cross product (and stand in
    // where it degenerates).
    const std::vector<Vec3> around = normal_sums([&](int i) { return limit[static_cast<size_t>(i)].v; });
    std::vector<Vec3> bp(nv), bn(nv);  // per topological vertex: the un-displaced surface
    for (size_t i = 0; i < nv; ++i) {
        bp[i] = limit[i].v;
        bn[i] = limit_normal(cross(du[i].v, dv[i].v), dot(du[i].v, du[i].v) + dot(dv[i].v, dv[i].v), around[i]);
    }

    // Displace each topological vertex once (uv seams share the displaced point: no cracks).
    std::vector<Vec3> pos = bp, nrm = bn;  // per topological vertex: the displaced surface
    if (s.displacement.active()) {
        std::vector<uint8_t> done(nv, 0);
        for (int f = 0; f < nf; ++f) {
            const auto fv = last.GetFaceVertices(f);
            const auto fuv = has_uv ? last.GetFaceFVarValues(f, 0) : Far::ConstIndexArray();
            for (int k = 0; k < fv.size(); ++k) {
                const auto i = static_cast<size_t>(fv[k]);
                if (done[i]) continue;
                done[i] = 1;
                const Vec2 uv = has_uv ? uvs[static_cast<size_t>(fuv[k])].v : Vec2{};
                pos[i] = bp[i] + bn[i] * s.displacement.offset(uv);
            }
        }
        nrm = normal_sums([&](int i) { return pos[static_cast<size_t>(i)]; });
        for (size_t i = 0; i < nv; ++i) nrm[i] = dot(nrm[i], nrm[i]) > 0 ? normalize(nrm[i]) : bn[i];
    }

    const std::vector<uint32_t> mat = diced_materials(c, *refiner, level);

    // Output vertices: one per (vertex, uv value) pair; positions repeat across uv seams.
    TriangleMesh m;
    std::unordered_map<uint64_t, uint32_t> out_index;
    auto vertex = [&](int v, int t) {
        const uint64_t key = (static_cast<uint64_t>(static_cast<uint32_t>(v)) << 32) | static_cast<uint32_t>(t);
        auto [it, fresh] = out_index.emplace(key, static_cast<uint32_t>(m.positions.size()));
        if (fresh) {
            const auto i = static_cast<size_t>(v);
            m.positions.push_back(pos[i]), m.normals.push_back(nrm[i]);
            m.base_positions.push_back(bp[i]), m.base_normals.push_back(bn[i]);
            if (has_uv) m.uvs.push_back(uvs[static_cast<size_t>(t)].v);
        }
        return it->second;
    };
    for (int f = 0; f < nf; ++f) {
        const auto fv = last.GetFaceVertices(f);
        const auto fuv = has_uv ? last.GetFaceFVarValues(f, 0) : Far::ConstIndexArray();
        uint32_t idx[4];
        for (int k = 0; k < fv.size() && k < 4; ++k) idx[k] = vertex(fv[k], has_uv ? fuv[k] : 0);
        for (int k = 1; k + 1 < fv.size() && k < 3; ++k) {  // a fan: one triangle, or two per quad
            m.indices.insert(m.indices.end(), {idx[0], idx[k], idx[k + 1]});
            m.face_materials.push_back(mat[static_cast<size_t>(f)]);
        }
    }
    return m;
}

}  // namespace bounce
