// The shading pass: the cache's interpolation (and the control variate's correction) or brute
// force's light, shaded into the frame's image, in tiles across processes.
#include "bounce/render/frame_passes.h"

#include <chrono>
#include <cstring>

#include "bounce/cache/control_variate.h"
#include "bounce/cache/passes.h"
#include "bounce/render/distributed.h"
#include "bounce/shade/layers.h"
#include "bounce/shade/shade.h"

namespace bounce {

namespace {

/// The fragments of every `step`-th window pixel in x and y; the other pixels empty.
DeepBuffer lattice_of(const DeepBuffer& deep, int step) {
    DeepBuffer out = deep;
    out.fragments.clear();
    out.offsets.assign(deep.pixel_count() + 1, 0);
    for (int wy = 0; wy < deep.height; ++wy)
        for (int wx = 0; wx < deep.width; ++wx) {
            const size_t i = static_cast<size_t>(wy) * deep.width + wx;
            if (wx % step == 0 && wy % step == 0) {
                auto f = deep.pixel(wx, wy);
                out.fragments.insert(out.fragments.end(), f.begin(), f.end());
            }
            out.offsets[i + 1] = static_cast<uint32_t>(out.fragments.size());
        }
    return out;
}

/// Each pixel of every layer takes the value of its step x step block's first pixel.
void fill_blocks(Image& img, int step) {
    for (Layer& l : img.layers) {
        const size_t nc = l.channels.size();
        for (int y = 0; y < img.height; ++y)
            for (int x = 0; x < img.width; ++x) {
                const float* src = img.at(l, x - x % step, y - y % step);
                std::copy_n(src, nc, img.at(l, x, y));
            }
    }
}

ShadeResult shade_window(const FrameContext& ctx, const ShadeStep& step, const DeepBuffer& deep, const IrradianceCache* cache,
                         const std::vector<Indirect>* brute, const SpecularSitesResult& specular, const RadiosityTextures* radiosity,
                         ProgressSink* progress) {
    const Scene& scene = ctx.scene;
    ShadeResult out;
    const SiteLightResult sites = site_light_for(ctx, step.sites, specular, window_of(deep), cache, radiosity);
    std::vector<Indirect> interpolated;
    LightShares shares;
    if (step.indirect == IndirectFrom::Cache) {
        auto t0 = std::chrono::steady_clock::now();
        // Per-light indirect layers: each light's share of the records' light parts.
        const bool per_light = step.per_light && cache->has_light_parts(scene.lights.size());
        InterpolatedLight light = interpolation_pass(scene, deep, *cache, ctx.plan.tiling(), ctx.stats, progress, true, per_light);
        ctx.stats.set("interpolation_s", std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
        interpolated = std::move(light.light);
        shares = std::move(light.shares);
        if (step.correction_rays > 0) {  // records as a control variate
            PhaseTimer timer(ctx.stats, "correction");
            GatherSettings gs = frame_gather_settings(ctx, false);
            gs.rays = step.correction_rays;
            const Gatherer gatherer(scene, ctx.accel, ctx.materials, ctx.lighting, radiosity, gs);
            correction_pass(scene, deep, *cache, gatherer, interpolated, ctx.stats, progress);
        }
        out.refined = fragment_mask(deep, light.refined);
        out.shading_misses = light.misses + sites.misses;
        if (specular.any()) ctx.stats.set("shading_misses", static_cast<double>(out.shading_misses));
        brute = &interpolated;
    }
    out.image =
        shade(scene, deep, ctx.materials, ctx.lighting, ctx.plan.shade(), step.indirect != IndirectFrom::None ? brute : nullptr, ctx.stats,
              progress, nullptr, sites.view(), step.deep_colour ? &out.colours : nullptr, shares.lights > 0 ? &shares : nullptr);
    return out;
}

/// Each process shades its tiles; rank 0 takes the whole image (the others' stays empty).
ShadeResult shade_in_tiles(const FrameContext& ctx, const ShadeStep& step, const DeepBuffer& deep, const IrradianceCache* cache,
                           const std::vector<Indirect>* brute, const SpecularSitesResult& specular, const RadiosityTextures* radiosity) {
    const auto tiles = in_tiles(ctx.comm, window_of(deep), ctx.plan.tiling().tile_size, TilesTo::First, [&](const std::array<int, 4>& w) {
        const DeepBuffer sub = sub_window(deep, w);
        const std::vector<Indirect> light = brute ? window_slice(deep, *brute, w) : std::vector<Indirect>();
        ShadeResult r = shade_window(ctx, step, sub, cache, brute ? &light : nullptr, specular, radiosity, nullptr);
        // The refined mask travels as a layer of the tile's image.
        if (!r.refined.empty()) add_mask_layer(r.image, r.refined, "refined");
        const uint64_t misses = r.shading_misses;
        return std::string(reinterpret_cast<const char*>(&misses), sizeof(misses)) + serialize_image(r.image);
    });
    ShadeResult out;
    if (ctx.comm.rank() != 0) return out;  // rank 0 writes the image
    std::vector<Image> images;
    for (const std::string& b : tiles) {
        uint64_t misses = 0;
        std::memcpy(&misses, b.data(), sizeof(misses));
        out.shading_misses += misses;
        images.push_back(parse_image(b.substr(sizeof(misses))));
    }
    out.image = assemble_tiles(window_of(deep), images);
    if (Layer* mask = out.image.find("refined")) {
        out.refined = std::move(mask->data);
        out.image.layers.pop_back();  // added back where one process adds it
    }
    ctx.stats.set("shading_misses", static_cast<double>(out.shading_misses));
    return out;
}

}  // namespace

ShadeResult shading_pass(const FrameContext& ctx, const ShadeStep& step, const DeepBuffer& deep, const IrradianceCache* cache,
                         const std::vector<Indirect>* brute, const SpecularSitesResult& specular, const RadiosityTextures* radiosity,
                         const std::function<void(const Image&)>& quick_look) {
    const Scene& scene = ctx.scene;
    PhaseTimer t(ctx.stats, "shading");
    if (step.quick_look && quick_look) {
        // A re-shade's quick look first: one pixel in 16 shaded exactly as the final image
        // shades it, standing for its 4x4 block.
        const DeepBuffer coarse = lattice_of(deep, 4);
        const InterpolatedLight light = interpolation_pass(scene, coarse, *cache, ctx.plan.tiling(), ctx.stats, nullptr);
        Image look = shade(scene, coarse, ctx.materials, ctx.lighting, ctx.plan.shade(), &light.light, ctx.stats, nullptr);
        fill_blocks(look, 4);
        quick_look(look);
    }
    if (ctx.comm.size() > 1) return shade_in_tiles(ctx, step, deep, cache, brute, specular, radiosity);
    return shade_window(ctx, step, deep, cache, brute, specular, radiosity, ctx.progress);
}

}  // namespace bounce
