#include "bounce/shade/shade.h"

#include <optional>

#include "bounce/core/parallel.h"
#include "bounce/shade/brdf.h"

namespace bounce {

namespace {

/// Emission plus direct light reflected by the fragment's bumped, glossy surface towards wo.
Color fragment_direct(const Scene& scene, const Materials& materials, const DirectLighting& lighting, const Fragment& f,
                      const SurfaceShading& surf, const Vec3& wo, int x, int y, uint32_t k, bool include_sky,
                      Counters& counters) {
    // Glossy surfaces reflect the same light samples the diffuse estimate draws.
    Color gloss(0);
    std::optional<LightSampleFn> glossy;
    if (surf.specular != Color(0))
        glossy.emplace([&](const Vec3& w, const Color& e) {
            gloss += ggx_specular(surf.normal, wo, w, surf.specular, surf.roughness) * e;
        });
    Color e = lighting.irradiance(f.p, surf.normal, f.object, fragment_stream(scene.render.visibility.seed, x, y, k),
                                  scene.render.lighting.light_samples, counters, include_sky, glossy ? &*glossy : nullptr);
    return materials.emission(f.material) + surf.albedo * e * kInvPi + gloss;
}

/// Emission-free direct light reflected by a strand towards wo: Kajiya-Kay over light samples
/// from both sides of the strand (light reaches a fibre from the whole sphere), with shadow
/// rays that skip the strand itself.
Color hair_direct(const Scene& scene, const DirectLighting& lighting, const Fragment& f, const Vec3& wo, int x, int y,
                  uint32_t k, bool include_sky, Counters& counters) {
    const Fur& fur = *scene.objects[f.object].fur;
    const Color albedo = fur.params.albedo(f.strand_v);
    Color out(0);
    for (int side = 0; side < 2; ++side) {
        const Vec3 n = side ? -f.n : f.n;
        // A sample's share of the irradiance is L dw cos(n, w): the fibre wants L dw.
        const LightSampleFn each = [&](const Vec3& w, const Color& e) {
            const float c = dot(n, w);
            if (c > 1e-6f) out += kajiya_kay(f.tangent, w, wo, albedo, fur.params.specular, fur.params.specular_exponent) * (e / c);
        };
        lighting.irradiance(f.p, n, f.object, fragment_stream(scene.render.visibility.seed, x, y, side ? k | 0x80000000u : k),
                            scene.render.lighting.light_samples, counters, include_sky, &each, fur.max_width());
    }
    return out;
}

/// The material where the camera sees fragment f; a strand has none (fur shades itself).
SurfaceShading fragment_surface(const Materials& materials, const Fragment& f) {
    return f.is_hair() ? SurfaceShading{} : materials.surface(f.material, f.object, f.prim, f.uv, f.n, f.footprint);
}

/// Direct light (and emission) leaving fragment k of pixel (x, y) towards wo: a strand's or a surface's.
Color direct_at(const Scene& scene, const Materials& materials, const DirectLighting& lighting, const Fragment& f,
                const SurfaceShading& surf, const Vec3& wo, int x, int y, uint32_t k, bool include_sky, Counters& counters) {
    return f.is_hair() ? hair_direct(scene, lighting, f, wo, x, y, k, include_sky, counters)
                       : fragment_direct(scene, materials, lighting, f, surf, wo, x, y, k, include_sky, counters);
}

/// The light direction of cached indirect light (luminance-weighted mean), or `fallback`.
Vec3 indirect_direction(const Indirect& in, const Vec3& fallback) {
    const Vec3 d = in.light_dir[0] * 0.2126f + in.light_dir[1] * 0.7152f + in.light_dir[2] * 0.0722f;
    return dot(d, d) > 1e-20f ? normalize(d) : fallback;
}

}  // namespace

Image shade(const Scene& scene, const DeepBuffer& deep, const Materials& materials,
            const DirectLighting& lighting, const std::vector<Indirect>* indirect, Stats& stats,
            ProgressSink* sink, const std::vector<Color>* direct_radiance) {
    const bool ao_only = scene.render.indirect.ao && indirect;
    Image img;
    img.full_width = deep.full_width, img.full_height = deep.full_height;
    img.x0 = deep.x0, img.y0 = deep.y0, img.width = deep.width, img.height = deep.height;
    Layer& beauty = img.add_layer("beauty", {"R", "G", "B", "A"});
    Layer* direct =
        ao_only ? nullptr : &img.add_layer("direct", {"direct.R", "direct.G", "direct.B"});
    Layer* ind = indirect && !ao_only
                     ? &img.add_layer("indirect", {"indirect.R", "indirect.G", "indirect.B"})
                     : nullptr;
    Layer* ao = indirect ? &img.add_layer("ao", {"ao.Y"}) : nullptr;
    Layer* bent =
        indirect ? &img.add_layer("bentnormal", {"bentnormal.X", "bentnormal.Y", "bentnormal.Z"})
                 : nullptr;
    Layer& albedo = img.add_layer("albedo", {"albedo.R", "albedo.G", "albedo.B"});
    Layer& normal = img.add_layer("N", {"N.X", "N.Y", "N.Z"});
    Layer& depth = img.add_layer("depth", {"Z"});

    CameraRays camera(scene.camera);
    auto put3 = [&](Layer* l, int x, int y, const Vec3& v) {
        if (!l) return;
        float* p = img.at(*l, x, y);
        p[0] = v.x, p[1] = v.y, p[2] = v.z;
    };

    for_each_pixel_in_tiles(
        deep, scene.render.parallel.tile_size, sink, "shading", [&](int wx, int wy, size_t first) {
            Counters& counters = stats.local();
            int x = wx + deep.x0, y = wy + deep.y0;
            Color b(0), d(0), a(0), e_ind(0);
            Vec3 n(0), bn(0);
            float cover = 0, held = 0, z = INFINITY, occl = 0;
            auto frags = deep.pixel(wx, wy);
            for (uint32_t k = 0; k < frags.size(); ++k) {
                const Fragment& f = frags[k];
                // A holdout: hides what is behind it and adds nothing, alpha included.
                if (scene.objects[f.object].matte) {
                    held += f.weight;
                    continue;
                }
                const bool hair = f.is_hair();
                const Fur* fur = hair ? scene.objects[f.object].fur.get() : nullptr;
                const SurfaceShading surf = fragment_surface(materials, f);
                const Color alb = hair ? fur->params.albedo(f.strand_v) : surf.albedo;
                const Vec3 wo = normalize(camera.origin() - f.p);
                if (indirect) {
                    const Indirect& in = (*indirect)[first + k];
                    // Baked AO of detail the gather cannot see; on hair the self-shadowing falloff.
                    const float w = f.weight * (hair ? fur->params.falloff(f.strand_v) : surf.occlusion);
                    e_ind += in.irradiance * w;
                    occl += in.ao * w;
                    bn += in.bent_normal * f.weight;
                    if (ao_only)
                        b += Color(in.ao) * w;
                    else if (hair)
                        b += hair_indirect(f.tangent, indirect_direction(in, f.n_base), f.n_base, wo, in.irradiance, alb,
                                           fur->params.specular, fur->params.specular_exponent) * w;
                    else
                        b += indirect_radiance(in, f.n, surf, wo, scene.render.shading.light_per_channel) * w;
                }
                if (!ao_only) {
                    Color radiance = direct_radiance ? (*direct_radiance)[first + k]
                                                     : direct_at(scene, materials, lighting, f, surf, wo, x, y, k,
                                                                 indirect == nullptr, counters);
                    d += radiance * f.weight;
                    b += radiance * f.weight;
                }
                a += alb * f.weight;
                n += f.n * f.weight;
                cover += f.weight;
                z = std::min(z, f.depth);
                ++counters.fragments_shaded;
            }
            if (cover + held < 1 && !ao_only) {
                // Escaping camera rays see the sky (in beauty and direct).
                Color bg = lighting.background(normalize(
                    camera.direction(static_cast<float>(x) + 0.5f, static_cast<float>(y) + 0.5f)));
                b += bg * (1 - cover - held);
                d += bg * (1 - cover - held);
            }
            float* pb = img.at(beauty, wx, wy);
            pb[0] = b.x, pb[1] = b.y, pb[2] = b.z, pb[3] = cover;
            put3(direct, wx, wy, d);
            put3(ind, wx, wy, e_ind);
            if (ao) *img.at(*ao, wx, wy) = occl;
            put3(bent, wx, wy, dot(bn, bn) > 0 ? normalize(bn) : Vec3(0));
            put3(&albedo, wx, wy, a);
            put3(&normal, wx, wy, cover > 0 ? normalize(n) : Vec3(0));
            *img.at(depth, wx, wy) = z;
        });
    return img;
}

std::vector<Color> fragment_direct_radiance(const Scene& scene, const DeepBuffer& deep, const Materials& materials,
                                            const DirectLighting& lighting, bool include_sky, Stats& stats) {
    std::vector<Color> out(deep.fragments.size());
    CameraRays camera(scene.camera);
    parallel_for_each_index(0, deep.height, [&](int wy) {
        Counters& counters = stats.local();
        for (int wx = 0; wx < deep.width; ++wx) {
            size_t first = deep.offsets[static_cast<size_t>(wy) * deep.width + wx];
            auto frags = deep.pixel(wx, wy);
            for (uint32_t k = 0; k < frags.size(); ++k) {
                const Fragment& f = frags[k];
                out[first + k] = direct_at(scene, materials, lighting, f, fragment_surface(materials, f),
                                           normalize(camera.origin() - f.p), wx + deep.x0, wy + deep.y0, k, include_sky, counters);
            }
        }
    });
    return out;
}

}  // namespace bounce
