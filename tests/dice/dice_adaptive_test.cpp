// Dicing per control edge (Bfr): one rate gives the uniform dicing, mixed rates stay
// watertight; a refined cage keeps its limit surface.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <tuple>

#include "bounce/dice/displacement.h"
#include "bounce/dice/subdivision.h"
#include "dice_util.h"
#include "test_util.h"

namespace bounce {
namespace {

using test::grid;
using test::write_map;

TEST(Dice, AdaptiveDicingAtOneRateIsTheUniformOne) {
    // Every edge at rate 2^L gives the points of dice at level L (the same limit surface, the
    // same parameter grid), displaced the same way.
    test::TempDir dir;
    SubdivSurface s;
    s.control = grid(4, true);
    for (Vec3& p : s.control.positions) p.z = 0.2f * std::sin(5 * p.x) * std::cos(3 * p.y);  // curved
    s.displacement.map = std::make_shared<DisplacementMap>(write_map(dir, "ramp.exr", 64, 8, [](float u, float) { return u; }));
    s.displacement.scale = 0.1f;
    const TriangleMesh a = dice(s, 3), b = dice_adaptive(s, [](const Vec3&, const Vec3&) { return 8; });
    EXPECT_EQ(a.triangle_count(), b.triangle_count());
    float worst = 0, worst_base = 0;
    for (size_t i = 0; i < b.positions.size(); ++i) {
        float nearest = INFINITY;
        size_t at = 0;
        for (size_t j = 0; j < a.positions.size(); ++j)
            if (const float d = length(b.base_positions[i] - a.base_positions[j]); d < nearest) nearest = d, at = j;
        worst_base = std::max(worst_base, nearest);
        worst = std::max(worst, length(b.positions[i] - a.positions[at]));
        EXPECT_NEAR(dot(b.base_normals[i], a.base_normals[at]), 1, 1e-4);
    }
    EXPECT_LT(worst_base, 1e-5f);
    EXPECT_LT(worst, 1e-4f);
}

TEST(Dice, AdaptiveDicingOfMixedRatesIsWatertight) {
    // Rates from 1 to 16 across a curved, displaced grid with a uv seam: every edge is shared by
    // exactly two triangles (matched by their end points' positions) but those on the grid's
    // border, as many as the border's control edges' rates add up to.
    test::TempDir dir;
    SubdivSurface s;
    s.control = grid(4, true);
    for (Vec3& p : s.control.positions) p.z = 0.2f * std::sin(5 * p.x) * std::cos(3 * p.y);
    s.displacement.map = std::make_shared<DisplacementMap>(write_map(dir, "ramp.exr", 64, 8, [](float u, float v) { return u * v; }));
    s.displacement.scale = 0.1f;
    auto rate = [](const Vec3& a, const Vec3& b) {
        return 1 << static_cast<int>(std::min(4.0f, 5 * (a.x + b.x) / 2));  // 1 at x = 0 .. 16 at x = 1
    };
    const TriangleMesh m = dice_adaptive(s, rate);
    auto key = [](const Vec3& p) { return std::make_tuple(p.x, p.y, p.z); };
    std::map<std::pair<std::tuple<float, float, float>, std::tuple<float, float, float>>, int> edges;
    for (size_t t = 0; t < m.indices.size(); t += 3)
        for (size_t k = 0; k < 3; ++k)
            ++edges[std::minmax(key(m.positions[m.indices[t + k]]), key(m.positions[m.indices[t + (k + 1) % 3]]))];
    size_t open = 0, shared = 0;
    for (const auto& [e, count] : edges) {
        EXPECT_LE(count, 2);
        open += count == 1, shared += count == 2;
    }
    int border = 0;  // the 16 control edges on the grid's border (4 x 4 grid of unit / 4 quads)
    for (int i = 0; i < 4; ++i) {
        const float x0 = static_cast<float>(i) / 4, x1 = static_cast<float>(i + 1) / 4;
        border += 2 * rate({x0, 0, 0}, {x1, 0, 0});                             // bottom and top
        border += rate({0, x0, 0}, {0, x1, 0}) + rate({1, x0, 0}, {1, x1, 0});  // left and right
    }
    EXPECT_EQ(open, static_cast<size_t>(border));
    EXPECT_GT(shared, 1000u);
}

TEST(Dice, ARefinedCageHasTheSameLimitSurface) {
    // A pyramid (a quad and four triangles): refined once it is all quads, and diced one level
    // less it gives the same points as the original cage.
    SubdivSurface s;
    ControlMesh& c = s.control;
    c.source = "pyramid.obj";
    c.positions = {{0, 0, 0}, {1, 0, 0}, {1, 0, 1}, {0, 0, 1}, {0.5f, 1, 0.5f}};
    c.face_sizes = {4, 3, 3, 3, 3};
    c.face_vertices = {0, 1, 2, 3, 1, 0, 4, 2, 1, 4, 3, 2, 4, 0, 3, 4};
    c.face_materials.assign(5, 0);
    SubdivSurface refined = s;
    refined.control = refine_cage(s, 1);
    ASSERT_EQ(refined.control.face_count(), 16u);
    for (int n : refined.control.face_sizes) EXPECT_EQ(n, 4);
    const TriangleMesh a = dice(s, 3), b = dice(refined, 2);
    ASSERT_EQ(a.positions.size(), b.positions.size());
    float worst = 0;
    for (const Vec3& p : a.positions) {
        float nearest = INFINITY;
        for (const Vec3& q : b.positions) nearest = std::min(nearest, length(p - q));
        worst = std::max(worst, nearest);
    }
    EXPECT_LT(worst, 1e-5f);
}

}  // namespace
}  // namespace bounce
