// Helpers of the dicing tests: displacement maps written as EXRs and a planar grid cage.
#pragma once

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <functional>
#include <string>
#include <vector>

#include "bounce/dice/subdivision.h"
#include "test_util.h"

namespace bounce::test {

/// A one-channel float EXR of f(u, v) at pixel centres (v up, as uvs are).
inline std::string write_map(const test::TempDir& dir, const std::string& name, int w, int h, const std::function<float(float, float)>& f) {
    std::vector<float> px(static_cast<size_t>(w) * h);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            px[static_cast<size_t>(y) * w + x] =
                f((static_cast<float>(x) + 0.5f) / static_cast<float>(w), 1 - (static_cast<float>(y) + 0.5f) / static_cast<float>(h));
    const std::string path = dir.file(name);
    auto out = OIIO::ImageOutput::create(path);
    OIIO::ImageSpec spec(w, h, 1, OIIO::TypeDesc::FLOAT);
    EXPECT_TRUE(out && out->open(path, spec) && out->write_image(OIIO::TypeDesc::FLOAT, px.data()) && out->close());
    return path;
}

/// An n x n grid of unit-square quads in z = 0 facing +z, uv = xy. With `seam`, the faces right
/// of x = 0.5 use their own uv values (v squeezed), so the grid has a uv seam down its middle.
inline ControlMesh grid(int n, bool seam = false) {
    ControlMesh c;
    c.source = "grid.obj";
    auto vid = [n](int i, int j) { return j * (n + 1) + i; };
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i)
            c.positions.push_back({static_cast<float>(i) / static_cast<float>(n), static_cast<float>(j) / static_cast<float>(n), 0});
    c.uvs.resize(c.positions.size());
    for (size_t k = 0; k < c.positions.size(); ++k) c.uvs[k] = {c.positions[k].x, c.positions[k].y};
    const int right = static_cast<int>(c.uvs.size());
    if (seam)
        for (const Vec3& p : c.positions) c.uvs.push_back({p.x, 0.3f + 0.5f * p.y});
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const int v[4] = {vid(i, j), vid(i + 1, j), vid(i + 1, j + 1), vid(i, j + 1)};
            const int off = seam && 2 * i >= n ? right : 0;
            c.face_sizes.push_back(4);
            for (int k : v) c.face_vertices.push_back(k), c.face_uvs.push_back(k + off);
            c.face_materials.push_back(0);
        }
    return c;
}

}  // namespace bounce::test
