// Vertex normals as authored (issue 61, item 2): a low-poly sphere OBJ with analytic `vn` gives
// the interpolated normal at every pixel, not its facets', whatever length its normals are
// written at (Sponza's OBJ has normals of length 1.63; Cycles normalises them on import).
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <fstream>
#include <sstream>

#include "bounce/render/render.h"
#include "test_util.h"

namespace bounce {
namespace {

using nlohmann::json;

/// A UV sphere of radius 1 at the origin, `seg` x `rings`: its vertices, triangles (1-based as
/// in the OBJ) and the OBJ text, with `vn` the unit position times `length(i)` for vertex i.
struct Ball {
    std::vector<std::array<double, 3>> v;
    std::vector<std::array<int, 3>> f;
    std::string obj;
};
Ball sphere(int seg, int rings, float (*length)(int)) {
    Ball b;
    std::ostringstream o;
    for (int r = 0; r <= rings; ++r)
        for (int s = 0; s <= seg; ++s) {
            const double th = kPi * static_cast<double>(r) / rings, ph = 2 * kPi * static_cast<double>(s) / seg;
            b.v.push_back({std::sin(th) * std::cos(ph), std::cos(th), std::sin(th) * std::sin(ph)});
            const auto& p = b.v.back();
            const double l = length(static_cast<int>(b.v.size()) - 1);
            o << "v " << p[0] << " " << p[1] << " " << p[2] << "\nvn " << p[0] * l << " " << p[1] * l << " " << p[2] * l << "\n";
        }
    for (int r = 0; r < rings; ++r)
        for (int s = 0; s < seg; ++s) {
            const int a = r * (seg + 1) + s + 1, bb = a + 1, c = a + seg + 1, d = c + 1;
            b.f.push_back({a, c, d}), b.f.push_back({a, d, bb});
        }
    for (const auto& t : b.f) o << "f " << t[0] << "//" << t[0] << " " << t[1] << "//" << t[1] << " " << t[2] << "//" << t[2] << "\n";
    b.obj = o.str();
    return b;
}

/// The unit-normal interpolation of `b`'s normals where the ray (o, d) first meets its
/// triangles (Moller-Trumbore in double); false on a miss.
bool interpolated_normal(const Ball& b, const double o[3], const double d[3], double out[3]) {
    double best = INFINITY;
    for (const auto& t : b.f) {
        const auto &p0 = b.v[t[0] - 1], &p1 = b.v[t[1] - 1], &p2 = b.v[t[2] - 1];
        double e1[3], e2[3], pv[3], tv[3], qv[3];
        for (int k = 0; k < 3; ++k) e1[k] = p1[k] - p0[k], e2[k] = p2[k] - p0[k], tv[k] = o[k] - p0[k];
        pv[0] = d[1] * e2[2] - d[2] * e2[1], pv[1] = d[2] * e2[0] - d[0] * e2[2], pv[2] = d[0] * e2[1] - d[1] * e2[0];
        const double det = e1[0] * pv[0] + e1[1] * pv[1] + e1[2] * pv[2];
        if (std::abs(det) < 1e-12) continue;
        const double u = (tv[0] * pv[0] + tv[1] * pv[1] + tv[2] * pv[2]) / det;
        qv[0] = tv[1] * e1[2] - tv[2] * e1[1], qv[1] = tv[2] * e1[0] - tv[0] * e1[2], qv[2] = tv[0] * e1[1] - tv[1] * e1[0];
        const double v = (d[0] * qv[0] + d[1] * qv[1] + d[2] * qv[2]) / det;
        const double dist = (e2[0] * qv[0] + e2[1] * qv[1] + e2[2] * qv[2]) / det;
        if (u < 0 || v < 0 || u + v > 1 || dist <= 0 || dist >= best) continue;
        best = dist;
        double len = 0;
        for (int k = 0; k < 3; ++k) out[k] = (1 - u - v) * p0[k] + u * p1[k] + v * p2[k], len += out[k] * out[k];
        for (int k = 0; k < 3; ++k) out[k] /= std::sqrt(len);
    }
    return best < INFINITY;
}

struct Angles {
    double worst = 0, mean = 0;
    size_t pixels = 0;
};

/// The N layer of `obj` seen head on against `b`'s interpolated unit normals where each pixel's
/// centre ray meets its triangles (16 subsamples a pixel: the fragment's normal is their mean).
Angles n_layer_error(const Ball& b, const std::string& obj) {
    test::TempDir dir;
    const json scene = {{"camera", {{"position", {0, 0, 5}}, {"look_at", {0, 0, 0}}, {"fov", 30}, {"resolution", {48, 48}}}},
                        {"render", {{"spp", 16}}},
                        {"lights", {{{"type", "sky"}, {"color", 1}}}},
                        {"objects", {{{"type", "mesh"}, {"file", dir.write("ball.obj", obj)}}}}};
    Stats stats;
    const Image img = render(test::scene_from(scene), {}, stats, nullptr).image;
    const Layer* n = img.find("N");
    Angles a;
    const double t = std::tan(15 * kPi / 180);
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) {
            const double dx = (2 * (x + 0.5) / img.width - 1) * t, dy = -(2 * (y + 0.5) / img.height - 1) * t;
            const double dn = std::sqrt(dx * dx + dy * dy + 1);
            const double d[3] = {dx / dn, dy / dn, -1 / dn}, o[3] = {0, 0, 5};
            double want[3];
            if (!interpolated_normal(b, o, d, want)) continue;
            // Away from the outline, where a pixel holds the ball alone.
            if (-(want[0] * d[0] + want[1] * d[1] + want[2] * d[2]) < 0.5) continue;
            const float* got = img.at(*n, x, y);
            double dot = 0;
            for (int k = 0; k < 3; ++k) dot += want[k] * got[k];
            const double angle = std::acos(std::min(1.0, dot)) * 180 / kPi;
            a.worst = std::max(a.worst, angle), a.mean += angle, ++a.pixels;
        }
    a.mean /= static_cast<double>(a.pixels);
    return a;
}

TEST(Normals, ALowPolySpheresAuthoredNormalsAreInterpolatedAtEveryPixel) {
    const Ball unit = sphere(12, 8, [](int) { return 1.0f; });
    const Angles a = n_layer_error(unit, unit.obj);
    ASSERT_GT(a.pixels, 500u);
    // The mean of a pixel's subsamples against its centre's; a facet's normal is up to 15 degrees off.
    EXPECT_LT(a.mean, 0.5);
    EXPECT_LT(a.worst, 2.0);
    // Normals written at other lengths (as Sponza's are) point the same way once normalised.
    const Ball scaled = sphere(12, 8, [](int i) { return i % 3 == 0 ? 1.63f : i % 3 == 1 ? 0.4f : 1.0f; });
    const Angles b = n_layer_error(unit, scaled.obj);
    EXPECT_LT(b.mean, 0.5);
    EXPECT_LT(b.worst, 2.0);
}

}  // namespace
}  // namespace bounce
