#include "bounce/shade/shade.h"

#include <tbb/parallel_for.h>

namespace bounce {

RandomStream fragment_stream(uint64_t seed, int x, int y, uint32_t k) {
    return RandomStream(seed, static_cast<uint64_t>(y) * 65536u + static_cast<uint64_t>(x), 1u + k);
}

Image shade(const Scene& scene, const DeepBuffer& deep, const Materials& materials,
            const DirectLighting& lighting, Stats& stats, ProgressSink* sink) {
    Image img;
    img.full_width = deep.full_width, img.full_height = deep.full_height;
    img.x0 = deep.x0, img.y0 = deep.y0, img.width = deep.width, img.height = deep.height;
    Layer& beauty = img.add_layer("beauty", {"R", "G", "B", "A"});
    Layer& direct = img.add_layer("direct", {"direct.R", "direct.G", "direct.B"});
    Layer& albedo = img.add_layer("albedo", {"albedo.R", "albedo.G", "albedo.B"});
    Layer& normal = img.add_layer("N", {"N.X", "N.Y", "N.Z"});
    Layer& depth = img.add_layer("depth", {"Z"});

    const int tile = scene.render.tile_size;
    const int tiles_x = (deep.width + tile - 1) / tile, tiles_y = (deep.height + tile - 1) / tile;
    CameraRays camera(scene.camera);
    Progress progress(sink, "shading", static_cast<uint64_t>(tiles_x) * tiles_y);

    tbb::parallel_for(0, tiles_x * tiles_y, [&](int t) {
        Counters& counters = stats.local();
        int tx0 = (t % tiles_x) * tile, ty0 = (t / tiles_x) * tile;
        for (int wy = ty0; wy < std::min(ty0 + tile, deep.height); ++wy)
            for (int wx = tx0; wx < std::min(tx0 + tile, deep.width); ++wx) {
                int x = wx + deep.x0, y = wy + deep.y0;
                Color b(0), d(0), a(0);
                Vec3 n(0);
                float cover = 0, z = INFINITY;
                auto frags = deep.pixel(wx, wy);
                for (uint32_t k = 0; k < frags.size(); ++k) {
                    const Fragment& f = frags[k];
                    Color alb = materials.albedo(f.material, f.uv);
                    Color e = lighting.irradiance(f.p, f.n, fragment_stream(deep.seed, x, y, k),
                                                  scene.render.light_samples, counters);
                    Color radiance = materials.emission(f.material) + alb * e * kInvPi;
                    d += radiance * f.weight;
                    a += alb * f.weight;
                    n += f.n * f.weight;
                    cover += f.weight;
                    z = std::min(z, f.depth);
                    ++counters.fragments_shaded;
                }
                b = d;
                if (cover < 1) {
                    Color bg = lighting.background(normalize(camera.direction(static_cast<float>(x) + 0.5f,
                                                                              static_cast<float>(y) + 0.5f)));
                    b += bg * (1 - cover);
                    d += bg * (1 - cover);
                }
                float* pb = img.at(beauty, wx, wy);
                pb[0] = b.x, pb[1] = b.y, pb[2] = b.z, pb[3] = cover;
                float* pd = img.at(direct, wx, wy);
                pd[0] = d.x, pd[1] = d.y, pd[2] = d.z;
                float* pa = img.at(albedo, wx, wy);
                pa[0] = a.x, pa[1] = a.y, pa[2] = a.z;
                Vec3 nn = cover > 0 ? normalize(n) : Vec3(0);
                float* pn = img.at(normal, wx, wy);
                pn[0] = nn.x, pn[1] = nn.y, pn[2] = nn.z;
                *img.at(depth, wx, wy) = z;
            }
        progress.add();
    });
    return img;
}

}  // namespace bounce
