#include "bounce/geometry/mesh.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <tuple>
#include <utility>

namespace bounce {

float TriangleMesh::triangle_area(size_t t) const {
    const Vec3& a = positions[indices[3 * t]];
    return 0.5f * length(cross(positions[indices[3 * t + 1]] - a, positions[indices[3 * t + 2]] - a));
}

double TriangleMesh::area() const {
    double sum = 0;
    for (size_t t = 0; t < triangle_count(); ++t) sum += triangle_area(t);
    return sum;
}

Bounds TriangleMesh::bounds() const {
    Bounds b;
    for (const auto& p : positions) b.extend(p);
    return b;
}

void TriangleMesh::transform(const Transform& t) {
    for (auto& p : positions) p = t.point(p);
    for (auto& n : normals) n = t.normal(n);
    for (auto& p : base_positions) p = t.point(p);
    for (auto& n : base_normals) n = t.normal(n);
}

void TriangleMesh::append(const TriangleMesh& o) {
    auto base = static_cast<uint32_t>(positions.size());
    // Keep optional attributes consistent: fill the side that lacks them.
    if (normals.empty() != o.normals.empty()) {
        if (normals.empty() && !positions.empty()) normals.assign(positions.size(), Vec3(0));
    }
    if (uvs.empty() != o.uvs.empty()) {
        if (uvs.empty() && !positions.empty()) uvs.assign(positions.size(), Vec2{});
    }
    if (colors.empty() && !o.colors.empty() && !positions.empty()) colors.assign(positions.size(), Color(1));
    // Dicing makes each displaced object's mesh whole; nothing appends to one.
    if (displaced() || o.displaced()) throw std::logic_error("TriangleMesh::append: displaced meshes are not appended");
    positions.insert(positions.end(), o.positions.begin(), o.positions.end());
    if (!o.normals.empty())
        normals.insert(normals.end(), o.normals.begin(), o.normals.end());
    else if (!normals.empty())
        normals.resize(positions.size(), Vec3(0));
    if (!o.uvs.empty())
        uvs.insert(uvs.end(), o.uvs.begin(), o.uvs.end());
    else if (!uvs.empty())
        uvs.resize(positions.size(), Vec2{});
    if (!o.colors.empty())
        colors.insert(colors.end(), o.colors.begin(), o.colors.end());
    else if (!colors.empty())
        colors.resize(positions.size(), Color(1));
    for (uint32_t i : o.indices) indices.push_back(i + base);
    face_materials.insert(face_materials.end(), o.face_materials.begin(), o.face_materials.end());
}

namespace {

/// One 1-to-4 split; `project` maps each new vertex (e.g. onto a sphere).
template <typename Project>
TriangleMesh split_once(const TriangleMesh& m, Project project) {
    TriangleMesh r;
    r.positions = m.positions;
    r.normals = m.normals;
    r.uvs = m.uvs;
    r.colors = m.colors;
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> midpoints;
    auto mid = [&](uint32_t a, uint32_t b) {
        auto key = std::minmax(a, b);
        auto it = midpoints.find(key);
        if (it != midpoints.end()) return it->second;
        auto idx = static_cast<uint32_t>(r.positions.size());
        r.positions.push_back((r.positions[a] + r.positions[b]) * 0.5f);
        if (!r.normals.empty()) r.normals.push_back(normalize(r.normals[a] + r.normals[b]));
        if (!r.uvs.empty()) r.uvs.push_back({(r.uvs[a].x + r.uvs[b].x) * 0.5f, (r.uvs[a].y + r.uvs[b].y) * 0.5f});
        if (!r.colors.empty()) r.colors.push_back(r.colors[a] + (r.colors[b] - r.colors[a]) * 0.5f);
        project(r, idx);
        midpoints.emplace(key, idx);
        return idx;
    };
    for (size_t t = 0; t < m.triangle_count(); ++t) {
        uint32_t a = m.indices[3 * t], b = m.indices[3 * t + 1], c = m.indices[3 * t + 2];
        uint32_t ab = mid(a, b), bc = mid(b, c), ca = mid(c, a);
        uint32_t tris[4][3] = {{a, ab, ca}, {ab, b, bc}, {ca, bc, c}, {ab, bc, ca}};
        for (auto& tri : tris) {
            r.indices.insert(r.indices.end(), {tri[0], tri[1], tri[2]});
            r.face_materials.push_back(m.face_materials[t]);
        }
    }
    return r;
}

/// Longitude-latitude uvs (u around y, v = 0 at the bottom pole). Vertices are split where a
/// triangle crosses the seam (u jumps by 1) or touches a pole (u taken from the other two), so
/// every triangle's uvs are continuous and tangents (bump mapping) are right.
TriangleMesh with_spherical_uvs(const TriangleMesh& m, const Vec3& center) {
    TriangleMesh r;
    r.face_materials = m.face_materials;
    std::map<std::tuple<uint32_t, float, float>, uint32_t> made;
    for (size_t t = 0; t < m.triangle_count(); ++t) {
        uint32_t id[3];
        Vec2 uv[3];
        bool pole[3];
        for (int k = 0; k < 3; ++k) {
            id[k] = m.indices[3 * t + static_cast<size_t>(k)];
            Vec3 d = normalize(m.positions[id[k]] - center);
            pole[k] = d.x * d.x + d.z * d.z < 1e-10f;
            uv[k] = {pole[k] ? 0.0f : 0.5f + std::atan2(d.z, d.x) / (2 * kPi), 1 - std::acos(std::clamp(d.y, -1.0f, 1.0f)) / kPi};
        }
        float umax = 0;
        for (int k = 0; k < 3; ++k)
            if (!pole[k]) umax = std::max(umax, uv[k].x);
        for (int k = 0; k < 3; ++k)
            if (!pole[k] && umax - uv[k].x > 0.5f) uv[k].x += 1;
        for (int k = 0; k < 3; ++k)
            if (pole[k]) uv[k].x = 0.5f * (uv[(k + 1) % 3].x + uv[(k + 2) % 3].x);
        for (int k = 0; k < 3; ++k) {
            auto [it, fresh] = made.try_emplace({id[k], uv[k].x, uv[k].y}, static_cast<uint32_t>(r.positions.size()));
            if (fresh) {
                r.positions.push_back(m.positions[id[k]]);
                r.normals.push_back(m.normals[id[k]]);
                r.uvs.push_back(uv[k]);
            }
            r.indices.push_back(it->second);
        }
    }
    return r;
}

}  // namespace

TriangleMesh subdivide_linear(const TriangleMesh& mesh, int levels) {
    TriangleMesh r = mesh;
    for (int i = 0; i < levels; ++i) r = split_once(r, [](TriangleMesh&, uint32_t) {});
    return r;
}

TriangleMesh make_icosphere(const Vec3& center, float radius, int level, uint32_t material) {
    const float t = (1.0f + std::sqrt(5.0f)) / 2.0f;
    TriangleMesh m;
    Vec3 v[12] = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                  {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
    for (auto& p : v) {
        m.normals.push_back(normalize(p));
        m.positions.push_back(center + normalize(p) * radius);
    }
    m.indices = {0, 11, 5, 0, 5, 1, 0, 1, 7, 0, 7, 10, 0, 10, 11, 1, 5, 9, 5, 11, 4,  11, 10, 2,  10, 7, 6, 7, 1, 8,
                 3, 9,  4, 3, 4, 2, 3, 2, 6, 3, 6, 8,  3, 8,  9,  4, 9, 5, 2, 4,  11, 6,  2,  10, 8,  6, 7, 9, 8, 1};
    m.face_materials.assign(20, material);
    auto onto_sphere = [&](TriangleMesh& r, uint32_t i) {
        Vec3 n = normalize(r.positions[i] - center);
        r.normals[i] = n;
        r.positions[i] = center + n * radius;
    };
    for (int i = 0; i < level; ++i) m = split_once(m, onto_sphere);
    return with_spherical_uvs(m, center);
}

TriangleMesh make_quad(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, uint32_t material) {
    TriangleMesh m;
    m.positions = {a, b, c, d};
    m.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    m.indices = {0, 1, 2, 0, 2, 3};
    m.face_materials = {material, material};
    return m;
}

}  // namespace bounce

namespace bounce {

std::pair<Vec3, Vec3> base_point(const TriangleMesh& m, uint32_t prim, float u, float v) {
    const uint32_t i0 = m.indices[3 * prim], i1 = m.indices[3 * prim + 1], i2 = m.indices[3 * prim + 2];
    const float w = 1 - u - v;
    const Vec3 p = m.base_positions[i0] * w + m.base_positions[i1] * u + m.base_positions[i2] * v;
    Vec3 n = m.base_normals[i0] * w + m.base_normals[i1] * u + m.base_normals[i2] * v;
    if (dot(n, n) < 1e-20f) n = cross(m.positions[i1] - m.positions[i0], m.positions[i2] - m.positions[i0]);
    return {p, normalize(n)};
}

Vec3 face_normal(const TriangleMesh& m, uint32_t prim) {
    const Vec3& a = m.positions[m.indices[3 * prim]];
    return normalize(cross(m.positions[m.indices[3 * prim + 1]] - a, m.positions[m.indices[3 * prim + 2]] - a));
}

std::array<Vec3, 3> triangle_vertices(const TriangleMesh& m, const Transform* to_world, uint32_t prim) {
    std::array<Vec3, 3> p;
    for (size_t k = 0; k < 3; ++k) {
        const Vec3& q = m.positions[m.indices[3 * prim + k]];
        p[k] = to_world ? to_world->point(q) : q;
    }
    return p;
}

Vec3 face_normal(const TriangleMesh& m, const Transform* to_world, uint32_t prim) {
    const auto [a, b, c] = triangle_vertices(m, to_world, prim);
    return normalize(cross(b - a, c - a));
}

SurfacePoint surface_point(const TriangleMesh& m, uint32_t prim, float u, float v) { return surface_point(m, nullptr, prim, u, v); }

SurfacePoint surface_point(const TriangleMesh& m, const Transform* to_world, uint32_t prim, float u, float v) {
    uint32_t i0 = m.indices[3 * prim], i1 = m.indices[3 * prim + 1], i2 = m.indices[3 * prim + 2];
    float w = 1 - u - v;
    SurfacePoint sp;
    const auto [a, b, c] = triangle_vertices(m, to_world, prim);
    sp.p = a * w + b * u + c * v;
    sp.ng = normalize(cross(b - a, c - a));
    sp.n = sp.ng;
    if (!m.normals.empty()) {
        const auto normal = [&](uint32_t i) { return to_world ? to_world->normal(m.normals[i]) : m.normals[i]; };
        Vec3 n = normal(i0) * w + normal(i1) * u + normal(i2) * v;
        if (dot(n, n) > 1e-12f) {
            sp.n = normalize(n);
            if (dot(sp.n, sp.ng) < 0) sp.ng = -sp.ng;  // geometric normal follows the authored side
        }
    }
    if (!m.uvs.empty()) {
        const Vec2 &ta = m.uvs[i0], &tb = m.uvs[i1], &tc = m.uvs[i2];
        sp.uv = {ta.x * w + tb.x * u + tc.x * v, ta.y * w + tb.y * u + tc.y * v};
    }
    sp.color = vertex_color(m, prim, u, v);
    sp.material = m.face_materials[prim];
    return sp;
}

Color vertex_color(const TriangleMesh& m, uint32_t prim, float u, float v) {
    if (m.colors.empty()) return Color(1);
    const Color &a = m.colors[m.indices[3 * prim]], &b = m.colors[m.indices[3 * prim + 1]], &c = m.colors[m.indices[3 * prim + 2]];
    return a + (b - a) * u + (c - a) * v;
}

Color vertex_color_at(const TriangleMesh& m, const Transform* to_world, uint32_t prim, const Vec3& p) {
    if (m.colors.empty()) return Color(1);
    const auto [a, b, c] = triangle_vertices(m, to_world, prim);
    // Barycentrics of p's projection (least squares on the two edges), clamped into the triangle.
    const Vec3 e1 = b - a, e2 = c - a, d = p - a;
    const float d11 = dot(e1, e1), d12 = dot(e1, e2), d22 = dot(e2, e2), det = d11 * d22 - d12 * d12;
    if (!(det > 0)) return vertex_color(m, prim, 0, 0);
    float u = (d22 * dot(d, e1) - d12 * dot(d, e2)) / det, v = (d11 * dot(d, e2) - d12 * dot(d, e1)) / det;
    u = std::clamp(u, 0.0f, 1.0f), v = std::clamp(v, 0.0f, 1.0f);
    if (u + v > 1) u /= u + v, v = 1 - u;
    return vertex_color(m, prim, u, v);
}

}  // namespace bounce
