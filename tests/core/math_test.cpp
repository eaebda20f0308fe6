// core/math.h against what it must be exactly: a Frame is orthonormal and right-handed for every
// normal (the two poles included) and its to_local undoes to_world; transforms compose, invert
// and carry normals as the inverse transpose does; Bounds grow and report emptiness.
#include <gtest/gtest.h>

#include <cmath>

#include "bounce/core/math.h"
#include "bounce/core/random.h"

namespace bounce {
namespace {

TEST(Math, AFrameIsOrthonormalAndRightHandedForEveryNormal) {
    RandomStream rng(3, 4);
    std::vector<Vec3> normals = {{0, 0, 1}, {0, 0, -1}, {1, 0, 0}, {0, -1, 0}, normalize(Vec3{1e-7f, 0, -1})};
    for (uint64_t i = 0; i < 2000; ++i)
        normals.push_back(normalize(Vec3{2 * rng.get(i, 0) - 1, 2 * rng.get(i, 1) - 1, 2 * rng.get(i, 2) - 1}));
    for (const Vec3& n : normals) {
        const Frame f(n);
        EXPECT_NEAR(length(f.s), 1, 1e-5f);
        EXPECT_NEAR(length(f.t), 1, 1e-5f);
        EXPECT_NEAR(dot(f.s, f.t), 0, 1e-5f);
        EXPECT_NEAR(dot(f.s, f.n), 0, 1e-5f);
        EXPECT_NEAR(dot(f.t, f.n), 0, 1e-5f);
        const Vec3 c = cross(f.s, f.t);  // right-handed: s x t = n
        EXPECT_NEAR(length(c - n), 0, 1e-5f) << n.x << " " << n.y << " " << n.z;
        const Vec3 v{0.3f, -0.5f, 0.81f};
        EXPECT_NEAR(length(f.to_local(f.to_world(v)) - v), 0, 1e-5f);
        EXPECT_NEAR(length(f.to_world({0, 0, 1}) - n), 0, 1e-6f);
    }
}

TEST(Math, TransformsComposeInvertAndCarryNormals) {
    const Transform a = Transform::translate({1, 2, 3}) * Transform::rotate(30, {1, 1, 0}) * Transform::scale({2, 0.5f, 3});
    const Vec3 p{0.7f, -1.1f, 2.5f};
    const Vec3 q = a.point(p);
    EXPECT_NEAR(length(a.inverse().point(q) - p), 0, 1e-5f);
    // Rotation by 90 degrees about z takes x to y, exactly up to rounding.
    const Vec3 y = Transform::rotate(90, {0, 0, 1}).vector({1, 0, 0});
    EXPECT_NEAR(y.x, 0, 1e-6f);
    EXPECT_NEAR(y.y, 1, 1e-6f);
    // A normal stays perpendicular to every transformed tangent (non-uniform scale included).
    const Vec3 n = normalize(Vec3{1, 2, 2}), t1 = normalize(cross(n, {0, 0, 1})), t2 = cross(n, t1);
    const Vec3 m = a.normal(n);
    EXPECT_NEAR(length(m), 1, 1e-5f);
    EXPECT_NEAR(dot(m, a.vector(t1)), 0, 1e-5f);
    EXPECT_NEAR(dot(m, a.vector(t2)), 0, 1e-5f);
    EXPECT_FLOAT_EQ(Transform::scale({2, 0.5f, 3}).largest_scale(), 3);
    EXPECT_TRUE(Transform::scale({1, 0, 1}).flattens());
    EXPECT_FALSE(Transform::scale({1e-6f, 1e-6f, 1e-6f}).flattens());  // tiny but whole
}

TEST(Math, BoundsGrowFromEmpty) {
    Bounds b;
    EXPECT_TRUE(b.empty());
    EXPECT_EQ(b.diagonal(), Vec3(0));
    b.extend({1, -2, 3});
    EXPECT_FALSE(b.empty());
    b.extend(Vec3{-1, 4, 3});
    EXPECT_EQ(b.lo, (Vec3{-1, -2, 3}));
    EXPECT_EQ(b.diagonal(), (Vec3{2, 6, 0}));
    EXPECT_FLOAT_EQ(luminance(Color(1)), 1.0f);  // the weights sum to one
}

}  // namespace
}  // namespace bounce
