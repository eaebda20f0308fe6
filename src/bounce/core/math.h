// Small fixed-size vector math used across every stage. Float, value types, header-only.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

namespace bounce {

inline constexpr float kPi = std::numbers::pi_v<float>;
inline constexpr float kInvPi = 1.0f / kPi;
/// Largest coordinate a scene, light or cache record may use: squared distances and BVH bounds
/// of such values still fit a float (Embree aborts on infinite bounds).
inline constexpr float kMaxCoordinate = 1e18f;
/// Largest radiometric value (intensity, radiance, irradiance) accepted from any input: sums
/// of many such values still fit a float.
inline constexpr float kMaxRadiometric = 1e20f;

struct Vec2 {
    float x = 0, y = 0;
    constexpr bool operator==(const Vec2&) const = default;
};

struct Vec3 {
    float x = 0, y = 0, z = 0;
    constexpr Vec3() = default;
    constexpr Vec3(float a, float b, float c) : x(a), y(b), z(c) {}
    constexpr explicit Vec3(float s) : x(s), y(s), z(s) {}
    constexpr float operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
    constexpr float& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
    constexpr Vec3 operator-() const { return {-x, -y, -z}; }
    constexpr Vec3& operator+=(const Vec3& o) {
        x += o.x;
        y += o.y;
        z += o.z;
        return *this;
    }
    constexpr Vec3& operator-=(const Vec3& o) {
        x -= o.x;
        y -= o.y;
        z -= o.z;
        return *this;
    }
    constexpr Vec3& operator*=(float s) {
        x *= s;
        y *= s;
        z *= s;
        return *this;
    }
    constexpr Vec3& operator*=(const Vec3& o) {
        x *= o.x;
        y *= o.y;
        z *= o.z;
        return *this;
    }
    constexpr Vec3& operator/=(float s) { return *this *= (1.0f / s); }
    constexpr bool operator==(const Vec3&) const = default;
};

/// RGB colour in linear scene-referred units.
using Color = Vec3;

constexpr Vec3 operator+(Vec3 a, const Vec3& b) { return a += b; }
constexpr Vec3 operator-(Vec3 a, const Vec3& b) { return a -= b; }
constexpr Vec3 operator*(Vec3 a, const Vec3& b) { return a *= b; }
constexpr Vec3 operator*(Vec3 a, float s) { return a *= s; }
constexpr Vec3 operator*(float s, Vec3 a) { return a *= s; }
constexpr Vec3 operator/(Vec3 a, float s) { return a /= s; }
constexpr float dot(const Vec3& a, const Vec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
constexpr Vec3 cross(const Vec3& a, const Vec3& b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
inline float length(const Vec3& a) { return std::sqrt(dot(a, a)); }
inline Vec3 normalize(const Vec3& a) {
    float l = length(a);
    return l > 0 ? a / l : Vec3(0, 0, 1);
}
inline Vec3 vmin(const Vec3& a, const Vec3& b) { return {std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)}; }
inline Vec3 vmax(const Vec3& a, const Vec3& b) { return {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)}; }
/// Every coordinate within [-limit, limit] (false for NaN).
inline bool within(const Vec3& v, float limit) { return std::fabs(v.x) <= limit && std::fabs(v.y) <= limit && std::fabs(v.z) <= limit; }
inline bool isfinite(const Vec3& a) { return std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z); }
/// Rec. 709 luminance.
constexpr float luminance(const Color& c) { return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z; }

/// Orthonormal frame around a unit normal (Duff et al. 2017, branchless).
struct Frame {
    Vec3 s, t, n;
    Frame() : s(1, 0, 0), t(0, 1, 0), n(0, 0, 1) {}
    explicit Frame(const Vec3& nn) : n(nn) {
        float sign = std::copysign(1.0f, n.z);
        float a = -1.0f / (sign + n.z);
        float b = n.x * n.y * a;
        s = {1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x};
        t = {b, sign + n.y * n.y * a, -n.y};
    }
    Vec3 to_world(const Vec3& v) const { return s * v.x + t * v.y + n * v.z; }
    Vec3 to_local(const Vec3& v) const { return {dot(v, s), dot(v, t), dot(v, n)}; }
};

/// Axis-aligned bounding box.
struct Bounds {
    Vec3 lo{INFINITY}, hi{-INFINITY};
    void extend(const Vec3& p) {
        lo = vmin(lo, p);
        hi = vmax(hi, p);
    }
    void extend(const Bounds& b) {
        lo = vmin(lo, b.lo);
        hi = vmax(hi, b.hi);
    }
    bool empty() const { return !(lo.x <= hi.x); }
    Vec3 diagonal() const { return empty() ? Vec3(0) : hi - lo; }
};

/// Affine 4x4 transform, row-major; points are column vectors.
struct Transform {
    std::array<float, 16> m{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};

    static Transform translate(const Vec3& t) {
        Transform r;
        r.m[3] = t.x;
        r.m[7] = t.y;
        r.m[11] = t.z;
        return r;
    }
    static Transform scale(const Vec3& s) {
        Transform r;
        r.m[0] = s.x;
        r.m[5] = s.y;
        r.m[10] = s.z;
        return r;
    }
    /// Rotation by `degrees` about `axis` (right-handed).
    static Transform rotate(float degrees, const Vec3& axis) {
        Vec3 a = normalize(axis);
        float th = degrees * kPi / 180.0f, c = std::cos(th), s = std::sin(th), t = 1 - c;
        Transform r;
        r.m = {t * a.x * a.x + c,
               t * a.x * a.y - s * a.z,
               t * a.x * a.z + s * a.y,
               0,
               t * a.x * a.y + s * a.z,
               t * a.y * a.y + c,
               t * a.y * a.z - s * a.x,
               0,
               t * a.x * a.z - s * a.y,
               t * a.y * a.z + s * a.x,
               t * a.z * a.z + c,
               0,
               0,
               0,
               0,
               1};
        return r;
    }
    Transform operator*(const Transform& o) const {
        Transform r;
        for (int i = 0; i < 4; ++i)
            for (int j = 0; j < 4; ++j) {
                float s = 0;
                for (int k = 0; k < 4; ++k) s += m[i * 4 + k] * o.m[k * 4 + j];
                r.m[i * 4 + j] = s;
            }
        return r;
    }
    Vec3 point(const Vec3& p) const {
        return {m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3], m[4] * p.x + m[5] * p.y + m[6] * p.z + m[7],
                m[8] * p.x + m[9] * p.y + m[10] * p.z + m[11]};
    }
    /// The most it stretches a length (the longest image of a unit axis).
    float largest_scale() const { return std::max({length(vector({1, 0, 0})), length(vector({0, 1, 0})), length(vector({0, 0, 1}))}); }
    Vec3 vector(const Vec3& v) const {
        return {m[0] * v.x + m[1] * v.y + m[2] * v.z, m[4] * v.x + m[5] * v.y + m[6] * v.z, m[8] * v.x + m[9] * v.y + m[10] * v.z};
    }
    /// Whether the transform flattens space (a zero scale, an all-zero or rank-2 matrix): it
    /// has no normals to give. Relative to the axes' lengths, so a tiny but whole scale is not.
    bool flattens() const {
        const Vec3 r0{m[0], m[1], m[2]}, r1{m[4], m[5], m[6]}, r2{m[8], m[9], m[10]};
        const double det = dot(r0, cross(r1, r2));
        const double scale = static_cast<double>(length(r0)) * length(r1) * length(r2);
        return !(std::abs(det) > 1e-6 * scale);
    }
    /// The inverse of an affine transform (identity when singular).
    Transform inverse() const {
        const Vec3 c0{m[0], m[4], m[8]}, c1{m[1], m[5], m[9]}, c2{m[2], m[6], m[10]};
        const Vec3 r0 = cross(c1, c2), r1 = cross(c2, c0), r2 = cross(c0, c1);
        const float det = dot(c0, r0);
        if (det == 0) return {};
        Transform r;
        r.m = {r0.x / det, r0.y / det, r0.z / det, 0, r1.x / det, r1.y / det, r1.z / det, 0,
               r2.x / det, r2.y / det, r2.z / det, 0, 0,          0,          0,          1};
        const Vec3 t = r.vector({m[3], m[7], m[11]});
        r.m[3] = -t.x, r.m[7] = -t.y, r.m[11] = -t.z;
        return r;
    }
    bool operator==(const Transform&) const = default;
    /// Transforms a normal by the inverse transpose of the upper 3x3 (cofactor matrix,
    /// which differs from it only by the determinant's scale; the result is normalized).
    Vec3 normal(const Vec3& n) const {
        Vec3 c0{m[0], m[4], m[8]}, c1{m[1], m[5], m[9]}, c2{m[2], m[6], m[10]};
        Vec3 r0 = cross(c1, c2), r1 = cross(c2, c0), r2 = cross(c0, c1);
        return normalize(r0 * n.x + r1 * n.y + r2 * n.z);
    }
};

}  // namespace bounce
