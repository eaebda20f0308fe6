#include "bounce/gather/hessian.h"

#include <array>
#include <cmath>

namespace bounce {

namespace {

using Mat3 = std::array<std::array<double, 3>, 3>;

struct DVec {
    double x = 0, y = 0, z = 0;
    DVec() = default;
    DVec(double a, double b, double c) : x(a), y(b), z(c) {}
    explicit DVec(const Vec3& v) : x(v.x), y(v.y), z(v.z) {}
    double operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
    DVec operator+(const DVec& o) const { return {x + o.x, y + o.y, z + o.z}; }
    DVec operator-(const DVec& o) const { return {x - o.x, y - o.y, z - o.z}; }
    DVec operator*(double s) const { return {x * s, y * s, z * s}; }
};
double dot(const DVec& a, const DVec& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
DVec cross(const DVec& a, const DVec& b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }

/// u v^T + v u^T, added to `m` with factor s.
void add_sym(Mat3& m, const DVec& u, const DVec& v, double s) {
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) m[i][j] += s * (u[i] * v[j] + u[j] * v[i]);
}

/// The Hessian of the form factor of the directed edge a -> b (vectors from the receiver)
/// with respect to the receiver's position, for receiver normal n. Summed over a polygon's
/// edges (in one orientation) it is the polygon's form-factor Hessian; the integrals I, J, K
/// are of the edge's parametrisation r(t) = a + t e, t in [0, 1] (the paper's Eqs.).
bool add_edge(Mat3& h, const DVec& a, const DVec& b, const DVec& n, double value) {
    const DVec e = b - a, c = cross(a, b);
    const double aa = dot(a, a), bb = dot(b, b), ee = dot(e, e), cc = dot(c, c);
    if (ee <= 1e-24 * (aa + bb) || cc <= 1e-18 * aa * bb) return false;  // degenerate: no area seen
    const double ea = dot(e, a), eb = dot(e, b);
    const double i1 = std::acos(std::clamp(dot(a, b) / std::sqrt(aa * bb), -1.0, 1.0)) / std::sqrt(cc);
    const double i2 = (eb / bb - ea / aa + ee * i1) / (2 * cc);
    const double j2 = ((1 / aa - 1 / bb) / 2 - ea * i2) / ee;
    const double i3 = (eb / (bb * bb) - ea / (aa * aa) + 3 * ee * i2) / (4 * cc);
    const double j3 = (1 / (aa * aa) - 1 / (bb * bb)) / (4 * ee) - ea * i3 / ee;
    const double k3 = (i2 - aa * i3 - 2 * ea * j3) / ee;
    const DVec v = a * i2 + e * j2;
    const double nc = dot(n, c);
    Mat3 m{};
    add_sym(m, cross(n, e), v, 1);
    add_sym(m, a, a, 2 * nc * i3);
    add_sym(m, e, e, 2 * nc * k3);
    add_sym(m, a, e, 4 * nc * j3);
    for (int i = 0; i < 3; ++i) m[i][i] -= nc * i2;
    const double s = -value / kPi;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) h[i][j] += s * m[i][j];
    return true;
}

}  // namespace

TangentHessian gather_hessian(const Vec3& p, const Vec3& n, int M, int N, std::span<const Vec3> points, std::span<const double> values,
                              std::span<const float> dist, ScratchBuffer& scratch) {
    Mat3 h{};
    const DVec o(p), nn(n);
    auto cell = [&](int j, int k) { return static_cast<size_t>(j * N + ((k % N) + N) % N); };
    auto rel = [&](int j, int k) { return DVec(points[cell(j, k)]) - o; };
    // The mesh: between rows j and j+1 two triangles per column, both clockwise seen from the
    // normal, A = (j,k) (j,k+1) (j+1,k) and B = (j+1,k+1) (j+1,k) (j,k+1); inside row 0 one
    // polygon, clockwise. A polygon's radiance is its farthest vertex's.
    auto farthest = [&](std::initializer_list<size_t> v) {
        size_t f = *v.begin();
        for (size_t c : v)
            if (dist[c] > dist[f]) f = c;
        return values[f];
    };
    const auto scope = scratch.scope();
    const std::span<double> va = scratch.take<double>(static_cast<size_t>(std::max(0, M - 1) * N), 0.0);  // per (j, k), j < M - 1
    const std::span<double> vb = scratch.take<double>(va.size(), 0.0);
    for (int j = 0; j + 1 < M; ++j)
        for (int k = 0; k < N; ++k) {
            va[cell(j, k)] = farthest({cell(j, k), cell(j, k + 1), cell(j + 1, k)});
            vb[cell(j, k)] = farthest({cell(j + 1, k + 1), cell(j + 1, k), cell(j, k + 1)});
        }
    double cap = values[cell(0, 0)];
    for (int k = 0; k < N; ++k)
        if (dist[cell(0, k)] > dist[cell(0, 0)]) cap = values[cell(0, k)];
    // Every edge once: the two polygons beside it traverse it in opposite directions, so it
    // contributes its Hessian (in one direction) times the difference of their radiances; edges
    // between equal radiances cancel and are skipped. The outer rim has one polygon only.
    auto edge = [&](int j0, int k0, int j1, int k1, double diff) {
        if (diff != 0) add_edge(h, rel(j0, k0), rel(j1, k1), nn, diff);
    };
    for (int j = 0; j < M; ++j)
        for (int k = 0; k < N; ++k) {
            const double inner = j + 1 < M ? va[cell(j, k)] : 0.0;  // A(j, k) runs (j,k) -> (j,k+1)
            const double outer = j == 0 ? (N >= 3 ? cap : 0.0) : vb[cell(j - 1, k)];
            edge(j, k, j, k + 1, inner - outer);
            if (j + 1 < M) {
                edge(j, k + 1, j + 1, k, va[cell(j, k)] - vb[cell(j, k)]);  // the diagonal
                edge(j + 1, k, j, k, va[cell(j, k)] - vb[cell(j, k - 1)]);  // the column at k
            }
        }

    // Restrict to the tangent plane and take the principal curvatures.
    const Frame f(n);
    const DVec s(f.s), t(f.t);
    auto quad = [&](const DVec& u, const DVec& v) {
        double r = 0;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) r += u[i] * h[i][j] * v[j];
        return r;
    };
    const double a = quad(s, s), b = quad(s, t), c = quad(t, t);
    const double mid = (a + c) / 2, rad = std::sqrt((a - c) * (a - c) / 4 + b * b);
    const double l1 = mid + rad, l2 = mid - rad;  // l1 >= l2
    TangentHessian out;
    const bool first_slow = std::fabs(l1) < std::fabs(l2);
    const double slow = first_slow ? l1 : l2;
    out.slow = static_cast<float>(std::fabs(slow));
    out.fast = static_cast<float>(std::fabs(first_slow ? l2 : l1));
    // Eigenvector of `slow`: (b, slow - a) or (slow - c, b), whichever is better conditioned.
    double vx = b, vy = slow - a;
    if (vx * vx + vy * vy < (slow - c) * (slow - c) + b * b) vx = slow - c, vy = b;
    const double len = std::sqrt(vx * vx + vy * vy);
    out.axis = len > 0 ? normalize(f.s * static_cast<float>(vx / len) + f.t * static_cast<float>(vy / len)) : f.s;
    return out;
}

}  // namespace bounce
