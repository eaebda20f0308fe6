// The shading pass: turns the fragments of a deep buffer into image layers: direct light
// (with shadows) for every fragment plus the indirect light handed in per fragment (from
// brute-force gathering or the irradiance cache).
#pragma once

#include "bounce/core/image.h"
#include "bounce/core/progress.h"
#include "bounce/core/stats.h"
#include "bounce/deep/deep_buffer.h"
#include "bounce/gather/gather.h"
#include "bounce/lighting/lighting.h"
#include "bounce/radiosity/radiosity.h"

namespace bounce {

/// Layers: beauty (R,G,B,A), direct, albedo, N, depth (Z); with `indirect` also indirect
/// (irradiance), ao (Y) and bentnormal. Beauty = emission + albedo E_direct / pi + the
/// indirect light through the surface's BRDF with its bumped normal (brdf.h; for an un-bumped
/// diffuse surface exactly albedo E_indirect / pi). Direct light is diffuse only, at the
/// bumped normal;
/// in AO-only mode (ShadeOptions::ao) beauty is the AO. Sky lights are left out of the direct
/// term when indirect light is given (the gather brings the sky). Tiles run in parallel; the
/// result is independent of thread count and tile order.
///
/// Mirrors and glass (specular.h): a fragment's own lobes are scaled by its base share, and its
/// specular paths add what they meet: the sky and quad lights, and the surfaces where they end
/// (sites), each shaded with direct light (its glossy lobe too) and the bounce light `sites`
/// gives it, or from the radiosity textures.
struct SiteLight {
    const DeepBuffer* sites = nullptr;             ///< specular_sites of this window (per pixel in trace order)
    const std::vector<Indirect>* light = nullptr;  ///< per site: its bounce light (null: none)
    const RadiosityTextures* radiosity = nullptr;  ///< indirect_at_specular_hits = radiosity: sites are looked up here
};
/// What the shading pass takes from the frame's plan: the seed and tiles, how light reaches the
/// BRDF and which layers it writes, and whether the render is of AO alone.
struct ShadeOptions {
    FrameTiling tiling;
    ShadingSettings shading;
    bool ao = false;
};
Image shade(const Scene& scene, const DeepBuffer& deep, const Materials& materials, const DirectLighting& lighting,
            const ShadeOptions& options, const std::vector<Indirect>* indirect, Stats& stats, ProgressSink* progress,
            const std::vector<Color>* direct_radiance = nullptr, const SiteLight& sites = {}, std::vector<Color>* colours = nullptr,
            const LightShares* shares = nullptr);
/// `colours` (if given) receives, parallel to deep.fragments, what each fragment adds to the
/// beauty (its coverage included; the sky seen past the fragments is no fragment's): the
/// colour of a deep file's samples (write_deep).
/// `shares` (if given, with components layers): each light's share of `indirect`, which the
/// per-light indirect layers split the fragments' indirect lobes by.

/// Emission plus direct light reflected towards the camera at every fragment, exactly as
/// `shade` computes it (bumped normal, glossy lobe, same random numbers): the progressive
/// preview re-shades after each sub-pass with it and so lights like the final image.
std::vector<Color> fragment_direct_radiance(const Scene& scene, const DeepBuffer& deep, const Materials& materials,
                                            const DirectLighting& lighting, uint64_t seed, bool include_sky, Stats& stats);

}  // namespace bounce
