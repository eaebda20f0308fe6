#include "bounce/shade/shade.h"

#include "bounce/core/parallel.h"
#include "bounce/core/scratch.h"
#include "bounce/shade/brdf.h"
#include "bounce/shade/components.h"
#include "bounce/specular/specular.h"

namespace bounce {

namespace {

/// Emission plus direct light reflected by the fragment's bumped, glossy surface towards wo;
/// with `parts`, also its components (per light as well when they are sized).
Color fragment_direct(const Materials& materials, const DirectLighting& lighting, uint64_t seed, const Fragment& f,
                      const SurfaceShading& surf, const Vec3& wo, int x, int y, uint32_t k, bool include_sky, Counters& counters,
                      ShadedParts* parts) {
    // Glossy surfaces reflect the same light samples the diffuse estimate draws.
    Color gloss(0);
    const bool glossy = surf.specular != Color(0), per_light = parts && !parts->light_diffuse.empty();
    const LightSampleFn each = [&](size_t light, const Vec3& w, const Color& e) {
        const Color g = glossy ? ggx_specular(surf.normal, wo, w, surf.specular, surf.roughness) * e : Color(0);
        gloss += g;
        if (per_light) parts->light_diffuse[light] += surf.albedo * e * kInvPi, parts->light_specular[light] += g;
    };
    const RandomStream rng = fragment_stream(seed, x, y, k);
    const int samples = lighting.settings().light_samples;
    Color e = lighting.irradiance(f.p, surf.normal, f.object, rng, samples, counters, include_sky, glossy || per_light ? &each : nullptr);
    const Color emission = materials.emission(f.material, f.uv);
    Color diffuse = surf.albedo * e * kInvPi;
    if (surf.translucency != Color(0)) {
        // A thin translucent surface: the light through its other side, diffusely transmitted.
        const LightSampleFn through = [&](size_t light, const Vec3&, const Color& eb) {
            parts->light_diffuse[light] += surf.translucency * eb * kInvPi;
        };
        diffuse += surf.translucency *
                   lighting.irradiance(f.p, -surf.normal, f.object, back_side_stream(rng), samples, counters, include_sky,
                                       per_light ? &through : nullptr) *
                   kInvPi;
    }
    if (parts) parts->emission = emission, parts->diffuse_direct = diffuse, parts->specular_direct = gloss;
    return emission + diffuse + gloss;
}

/// Emission-free direct light reflected by a strand towards wo: Kajiya-Kay over light samples
/// from both sides of the strand (light reaches a fibre from the whole sphere), with shadow
/// rays that skip the strand itself.
Color hair_direct(const Scene& scene, const DirectLighting& lighting, uint64_t seed, const Fragment& f, const Vec3& wo, int x, int y,
                  uint32_t k, bool include_sky, Counters& counters, ShadedParts* parts) {
    const Fur& fur = *scene.objects[f.object].fur;
    const Color albedo = fur.params.albedo(f.strand_v);
    Color out(0);
    for (int side = 0; side < 2; ++side) {
        const Vec3 n = side ? -f.n : f.n;
        // A sample's share of the irradiance is L dw cos(n, w): the fibre wants L dw.
        const LightSampleFn each = [&](size_t light, const Vec3& w, const Color& e) {
            const float c = dot(n, w);
            if (c <= 1e-6f) return;
            const Color kk = kajiya_kay(f.tangent, w, wo, albedo, fur.params.specular, fur.params.specular_exponent) * (e / c);
            out += kk;
            if (parts && !parts->light_diffuse.empty()) parts->light_diffuse[light] += kk;
        };
        lighting.irradiance(f.p, n, f.object, fragment_stream(seed, x, y, side ? k | 0x80000000u : k), lighting.settings().light_samples,
                            counters, include_sky, &each, fur.max_width());
    }
    if (parts) parts->diffuse_direct = out;  // a strand's lobes are one (Kajiya-Kay): all in diffuse
    return out;
}

/// The material where the camera sees fragment f; a strand has none (fur shades itself).
SurfaceShading fragment_surface(const Materials& materials, const Fragment& f) {
    return f.is_hair() ? SurfaceShading{} : materials.surface(f.material, f.object, f.prim, f.p, f.uv, f.n, f.footprint);
}

/// Direct light (and emission) leaving fragment k of pixel (x, y) towards wo: a strand's or a surface's.
Color direct_at(const Scene& scene, const Materials& materials, const DirectLighting& lighting, uint64_t seed, const Fragment& f,
                const SurfaceShading& surf, const Vec3& wo, int x, int y, uint32_t k, bool include_sky, Counters& counters,
                ShadedParts* parts = nullptr) {
    return f.is_hair() ? hair_direct(scene, lighting, seed, f, wo, x, y, k, include_sky, counters, parts)
                       : fragment_direct(materials, lighting, seed, f, surf, wo, x, y, k, include_sky, counters, parts);
}

/// The light direction of cached indirect light (luminance-weighted mean), or `fallback`.
Vec3 indirect_direction(const Indirect& in, const Vec3& fallback) {
    const Vec3 d = in.light_dir[0] * 0.2126f + in.light_dir[1] * 0.7152f + in.light_dir[2] * 0.0722f;
    return dot(d, d) > 1e-20f ? normalize(d) : fallback;
}

/// What fragment f's `indirect` layer holds: the irradiance its diffuse lobes scatter, E through
/// its front and, on a thin translucent surface, t E_back + (1 - t) E_front.
Color indirect_layer(const Scene& scene, const Fragment& f, const Indirect& in) {
    if (f.is_hair()) return in.irradiance;
    const float t = scene.materials[f.material].diffuse_transmission;
    return t > 0 ? in.irradiance * (1 - t) + in.back * t : in.irradiance;
}

/// What one pixel's fragments add up to, layer by layer.
struct PixelSum {
    Color beauty{0}, direct{0}, albedo{0}, indirect{0};
    Vec3 n{0}, bent{0};
    float cover = 0, held = 0, z = INFINITY, ao = 0;
    float largest = 0;  ///< weight of the fragment the id layer names
    uint32_t object = 0, material = 0;
};

/// The shading pass's fixed inputs.
struct ShadeContext {
    const Scene& scene;
    const ShadeOptions& options;
    const Materials& materials;
    const DirectLighting& lighting;
    const std::vector<Indirect>* indirect;
    const std::vector<Color>* direct_radiance;
    const CameraRays& camera;
    bool ao_only;
    const SpecularTracer& tracer;
    const SiteLight& sites;
    const LightShares* shares;
};

/// The bounce light a translucent surface lets through from its back side (Indirect::back),
/// diffusely; 0 on an opaque one.
Color transmitted_indirect(const SurfaceShading& surf, const Indirect& in) { return surf.translucency * in.back * kInvPi; }

/// Site j of a pixel: the random stream of its light samples is its pixel's, after every fragment's.
constexpr uint32_t kSiteStream = 256;

/// Radiance leaving a specular path's site back along the path: emission, direct light through
/// its diffuse and glossy lobes, and its bounce light `in` (null: none); or the radiosity textures' value.
Color site_radiance(const ShadeContext& c, const PathSite& s, int x, int y, uint32_t j, const Indirect* in, Counters& counters) {
    const Fragment& f = s.at;
    if (c.sites.radiosity)
        return c.materials.emission(f.material, f.uv) + c.sites.radiosity->lookup(f.object, f.prim, s.u, s.v, s.front, counters);
    const Material& m = c.scene.materials[f.material];
    SurfaceShading surf;
    surf.albedo = c.materials.albedo(f.material, f.uv) * c.materials.vertex_color(f.object, f.prim, f.p);
    surf.translucency = c.materials.translucency(f.material, f.uv);
    surf.specular = m.specular, surf.roughness = m.roughness, surf.normal = f.n;
    Color out = fragment_direct(c.materials, c.lighting, c.options.tiling.seed, f, surf, s.wo, x, y, kSiteStream + j, c.indirect == nullptr,
                                counters, nullptr);
    if (in) out += indirect_radiance(*in, f.n, surf, s.wo, c.options.shading.light_per_channel) + transmitted_indirect(surf, *in);
    return out;
}

/// Adds what the specular paths of a pixel's fragments bring (paths.sites shaded) to `sum`.
/// `colours` (if given): the pixel's fragments' entries of shade's `colours`.
void add_paths(const ShadeContext& c, const PixelPaths& paths, std::span<const Fragment> frags, int x, int y, int wx, int wy, PixelSum& sum,
               ComponentLayers& comps, Counters& counters, Color* colours) {
    const auto held = [&](uint32_t k) { return c.scene.objects[frags[k].object].matte; };
    for (uint32_t k = 0; k < frags.size(); ++k) {
        if (held(k)) continue;
        const Color r = paths.seen_reflection[k] * frags[k].weight, t = paths.seen_refraction[k] * frags[k].weight;
        sum.beauty += r + t;
        if (colours) colours[k] += r + t;
        if (comps.on()) comps.add_specular(wx, wy, false, r), comps.add_specular(wx, wy, true, t);
    }
    // The light the passes before gave each site, when they traced the same sites.
    const DeepBuffer* given = c.sites.sites;
    const size_t first = given ? given->offsets[static_cast<size_t>(wy) * given->width + wx] : 0;
    const bool matched = given && c.sites.light && given->pixel(wx, wy).size() == paths.sites.size();
    for (uint32_t j = 0; j < paths.sites.size(); ++j) {
        const PathSite& s = paths.sites[j];
        if (held(s.fragment)) continue;
        const Indirect* in = matched ? &(*c.sites.light)[first + j] : nullptr;
        const Color L = site_radiance(c, s, x, y, j, in, counters) * s.weight * frags[s.fragment].weight;
        sum.beauty += L;
        if (colours) colours[s.fragment] += L;
        if (comps.on()) comps.add_specular(wx, wy, s.kind == PathKind::Refraction, L);
    }
}

/// Adds fragment k of pixel (x, y) (its index `at` in the deep buffer) to `sum`; with layer
/// components on, also to `comps` at window pixel (wx, wy).
/// `base`: the share of the light its own lobes reflect (a mirror's or glass's base share, else 1).
void shade_fragment(const ShadeContext& c, const Fragment& f, int x, int y, uint32_t k, size_t at, const Color& base, PixelSum& sum,
                    ComponentLayers& comps, int wx, int wy, Counters& counters) {
    // A holdout: hides what is behind it and adds nothing, alpha included.
    if (c.scene.objects[f.object].matte) {
        sum.held += f.weight;
        return;
    }
    const bool hair = f.is_hair();
    const Fur* fur = hair ? c.scene.objects[f.object].fur.get() : nullptr;
    const SurfaceShading surf = fragment_surface(c.materials, f);
    // The albedo layer: all the surface scatters diffusely, reflected and transmitted (what a denoiser wants).
    const Color alb = hair ? fur->params.albedo(f.strand_v) : surf.albedo + surf.translucency;
    const Vec3 wo = normalize(c.camera.origin() - f.p);
    if (c.indirect) {
        const Indirect& in = (*c.indirect)[at];
        // Baked AO of detail the gather cannot see; on hair the self-shadowing falloff.
        const float w = f.weight * (hair ? fur->params.falloff(f.strand_v) : surf.occlusion);
        sum.indirect += indirect_layer(c.scene, f, in) * w;
        sum.ao += in.ao * w;
        sum.bent += in.bent_normal * f.weight;
        IndirectLobes lobes;
        if (c.ao_only)
            lobes.diffuse = Color(in.ao);
        else if (hair)
            lobes.diffuse = hair_indirect(f.tangent, indirect_direction(in, f.n_base), f.n_base, wo, in.irradiance, alb,
                                          fur->params.specular, fur->params.specular_exponent);
        else
            lobes = indirect_lobes(in, f.n, surf, wo, c.options.shading.light_per_channel);
        lobes.diffuse += transmitted_indirect(surf, in);
        lobes.diffuse *= base, lobes.specular *= base;
        sum.beauty += (lobes.diffuse + lobes.specular) * w;
        if (comps.on())
            comps.add_indirect(wx, wy, lobes.diffuse, lobes.specular, w, c.shares ? c.shares->at(at) : std::span<const Color>());
    }
    if (!c.ao_only) {
        ShadedParts parts = comps.on() ? comps.parts() : ShadedParts{};
        const Color radiance =
            base * (c.direct_radiance && !comps.on() ? (*c.direct_radiance)[at]
                                                     : direct_at(c.scene, c.materials, c.lighting, c.options.tiling.seed, f, surf, wo, x, y,
                                                                 k, c.indirect == nullptr, counters, comps.on() ? &parts : nullptr));
        parts.scale(base);
        sum.direct += radiance * f.weight;
        sum.beauty += radiance * f.weight;
        if (comps.on()) comps.add(wx, wy, parts, f.weight);
    }
    sum.albedo += alb * f.weight;
    sum.n += f.n * f.weight;
    sum.cover += f.weight;
    sum.z = std::min(sum.z, f.depth);
    if (f.weight > sum.largest) sum.largest = f.weight, sum.object = f.object, sum.material = f.material;
    ++counters.fragments_shaded;
}

}  // namespace

Image shade(const Scene& scene, const DeepBuffer& deep, const Materials& materials, const DirectLighting& lighting,
            const ShadeOptions& options, const std::vector<Indirect>* indirect, Stats& stats, ProgressSink* sink,
            const std::vector<Color>* direct_radiance, const SiteLight& sites, std::vector<Color>* colours, const LightShares* shares) {
    if (colours) colours->assign(deep.fragments.size(), Color(0));
    const bool ao_only = options.ao && indirect;
    Image img;
    img.full_width = deep.full_width, img.full_height = deep.full_height;
    img.x0 = deep.x0, img.y0 = deep.y0, img.width = deep.width, img.height = deep.height;
    Layer& beauty = img.add_layer("beauty", {"R", "G", "B", "A"});
    Layer* direct = ao_only ? nullptr : &img.add_layer("direct", {"direct.R", "direct.G", "direct.B"});
    Layer* ind = indirect && !ao_only ? &img.add_layer("indirect", {"indirect.R", "indirect.G", "indirect.B"}) : nullptr;
    Layer* ao = indirect ? &img.add_layer("ao", {"ao.Y"}) : nullptr;
    Layer* bent = indirect ? &img.add_layer("bentnormal", {"bentnormal.X", "bentnormal.Y", "bentnormal.Z"}) : nullptr;
    Layer& albedo = img.add_layer("albedo", {"albedo.R", "albedo.G", "albedo.B"});
    Layer& normal = img.add_layer("N", {"N.X", "N.Y", "N.Z"});
    Layer& depth = img.add_layer("depth", {"Z"});
    // AO-only renders have no components to split.
    ComponentLayers comps(img, scene, options.shading.layers == LayerSet::Components && !ao_only, shares != nullptr);

    CameraRays camera(scene.camera);
    const SpecularTracer tracer(scene, lighting.accel(), lighting, materials, options.shading.specular_depth);
    const bool specular = tracer.active() && !ao_only;  // AO-only renders show no reflections
    const ShadeContext ctx{scene, options, materials, lighting, indirect, direct_radiance, camera, ao_only, tracer, sites, shares};
    auto put3 = [&](Layer* l, int x, int y, const Vec3& v) {
        if (!l) return;
        float* p = img.at(*l, x, y);
        p[0] = v.x, p[1] = v.y, p[2] = v.z;
    };

    PerThread<PixelPaths> paths_per_thread;  // a pixel's specular paths, reused by the thread's next pixel
    for_each_pixel_in_tiles(deep, options.tiling.tile_size, sink, "shading", [&](int wx, int wy, size_t first) {
        Counters& counters = stats.local();
        int x = wx + deep.x0, y = wy + deep.y0;
        PixelSum sum;
        auto frags = deep.pixel(wx, wy);
        PixelPaths& paths = paths_per_thread.local();
        if (specular) tracer.trace(frags, camera.origin(), paths, counters);
        for (uint32_t k = 0; k < frags.size(); ++k) {
            const Color before = sum.beauty;
            shade_fragment(ctx, frags[k], x, y, k, first + k, specular ? paths.base[k] : Color(1), sum, comps, wx, wy, counters);
            if (colours) (*colours)[first + k] = sum.beauty - before;
        }
        if (specular) add_paths(ctx, paths, frags, x, y, wx, wy, sum, comps, counters, colours ? colours->data() + first : nullptr);
        if (const float open = 1 - sum.cover - sum.held; open > 0 && !ao_only) {
            // Escaping camera rays see the sky (in beauty and direct).
            const Color seen =
                lighting.background(normalize(camera.direction(static_cast<float>(x) + 0.5f, static_cast<float>(y) + 0.5f))) * open;
            sum.beauty += seen;
            sum.direct += seen;
            if (comps.on()) comps.background(wx, wy, seen);
        }
        if (comps.on() && sum.largest > 0) comps.ids(wx, wy, sum.object, sum.material);
        float* pb = img.at(beauty, wx, wy);
        pb[0] = sum.beauty.x, pb[1] = sum.beauty.y, pb[2] = sum.beauty.z, pb[3] = sum.cover;
        put3(direct, wx, wy, sum.direct);
        put3(ind, wx, wy, sum.indirect);
        if (ao) *img.at(*ao, wx, wy) = sum.ao;
        put3(bent, wx, wy, dot(sum.bent, sum.bent) > 0 ? normalize(sum.bent) : Vec3(0));
        put3(&albedo, wx, wy, sum.albedo);
        put3(&normal, wx, wy, sum.cover > 0 ? normalize(sum.n) : Vec3(0));
        *img.at(depth, wx, wy) = sum.z;
    });
    return img;
}

std::vector<Color> fragment_direct_radiance(const Scene& scene, const DeepBuffer& deep, const Materials& materials,
                                            const DirectLighting& lighting, uint64_t seed, bool include_sky, Stats& stats) {
    std::vector<Color> out(deep.fragments.size());
    CameraRays camera(scene.camera);
    parallel_for_each_index(0, deep.height, [&](int wy) {
        Counters& counters = stats.local();
        for (int wx = 0; wx < deep.width; ++wx) {
            size_t first = deep.offsets[static_cast<size_t>(wy) * deep.width + wx];
            auto frags = deep.pixel(wx, wy);
            for (uint32_t k = 0; k < frags.size(); ++k) {
                const Fragment& f = frags[k];
                out[first + k] = direct_at(scene, materials, lighting, seed, f, fragment_surface(materials, f),
                                           normalize(camera.origin() - f.p), wx + deep.x0, wy + deep.y0, k, include_sky, counters);
            }
        }
    });
    return out;
}

}  // namespace bounce
