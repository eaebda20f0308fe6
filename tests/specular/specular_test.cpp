// Mirrors and glass against analytic cases: Fresnel, a mirror's image of a known emitter, a
// glass slab's lateral shift, a sphere's Fresnel at normal and grazing incidence, energy
// conservation of a clear sphere under a uniform sky; a normal map's tilt of a mirror; visibility to reflections; the cache
// covering every site of the bundled mirror/glass scene before the shading pass.
#include <gtest/gtest.h>

#include <cmath>

#include "bounce/core/image.h"
#include "bounce/lighting/materials.h"
#include "bounce/render/render.h"
#include "bounce/specular/specular.h"
#include "test_util.h"

namespace bounce {
namespace {

using nlohmann::json;

Image render_image(const Scene& s, Stats* out = nullptr) {
    Stats stats;
    Image img = render(s, {}, stats, nullptr).image;
    if (out) *out = std::move(stats);
    return img;
}

float at(const Image& img, const std::string& layer, int x, int y, int c = 0) {
    const Layer* l = img.find(layer);
    EXPECT_TRUE(l) << layer;
    return l ? img.at(*l, x, y)[c] : NAN;
}

TEST(Fresnel, NormalIncidenceBrewsterGrazingAndTotalInternalReflection) {
    EXPECT_NEAR(fresnel_dielectric(1, 1.5f), 0.04f, 1e-6f);  // ((1 - n) / (1 + n))^2
    EXPECT_NEAR(fresnel_dielectric(1, 1 / 1.5f), 0.04f, 1e-6f);
    // At Brewster's angle (tan = n) p-polarised light is not reflected: F = rs^2 / 2.
    const float tb = std::atan(1.5f), ci = std::cos(tb), ct = std::cos(kPi / 2 - tb);
    const float rs = (ci - 1.5f * ct) / (ci + 1.5f * ct);
    EXPECT_NEAR(fresnel_dielectric(ci, 1.5f), 0.5f * rs * rs, 1e-6f);
    EXPECT_NEAR(fresnel_dielectric(0, 1.5f), 1.0f, 1e-6f);
    // Inside glass beyond the critical angle (sin = 1/1.5): everything is reflected.
    EXPECT_EQ(fresnel_dielectric(std::cos(0.8f), 1 / 1.5f), 1.0f);
    // Reciprocity: the same boundary crossed either way reflects the same share.
    const float c1 = std::cos(0.6f), c2 = std::sqrt(1 - std::pow(std::sin(0.6f) / 1.5f, 2.0f));
    EXPECT_NEAR(fresnel_dielectric(c1, 1.5f), fresnel_dielectric(c2, 1 / 1.5f), 1e-6f);
}

TEST(Fresnel, TheSplitOfAnyMaterialSumsToOne) {
    Material m;
    m.mirror = {0.3f, 0.5f, 0.9f}, m.transmission = {1, 0.4f, 0.2f}, m.ior = 1.7f;
    for (float c : {1.0f, 0.7f, 0.2f, 0.01f})
        for (bool entering : {true, false}) {
            const SpecularSplit s = specular_split(m, c, entering);
            for (int ch = 0; ch < 3; ++ch) EXPECT_NEAR(s.reflect[ch] + s.transmit[ch] + s.base[ch], 1.0f, 1e-6f);
        }
}

/// A mirror at z = 0 facing the camera (z = 5); behind the camera, an emitter covering the
/// left half of what the mirror shows; a sky of radiance 0.5 elsewhere.
json mirror_scene(const json& card = nullptr) {
    json j = {
        {"camera", {{"position", {0, 0, 5}}, {"look_at", {0, 0, 0}}, {"fov", 20}, {"resolution", {16, 16}}}},
        {"render", {{"gi", "none"}, {"spp", 4}}},
        {"materials",
         {{"mirror", {{"color", 0}, {"mirror", {0.8, 0.6, 0.4}}}},
          {"emitter", {{"color", 0}, {"emission", {2, 3, 4}}}},
          {"black", {{"color", 0}}}}},
        {"lights", {{{"type", "sky"}, {"color", 0.5}}}},
        {"objects",
         {{{"name", "mirror"}, {"type", "quad"}, {"material", "mirror"}, {"vertices", {{-5, -5, 0}, {5, -5, 0}, {5, 5, 0}, {-5, 5, 0}}}},
          {{"name", "emitter"},
           {"type", "quad"},
           {"material", "emitter"},
           {"vertices", {{-50, -50, 10}, {-50, 50, 10}, {0, 50, 10}, {0, -50, 10}}}}}}};
    if (!card.is_null()) j["objects"].push_back(card);
    return j;
}

TEST(Mirror, ShowsAKnownEmitterAndTheSkyTimesItsTint) {
    const Image img = render_image(test::scene_from(mirror_scene()));
    const float tints[3] = {0.8f, 0.6f, 0.4f}, emitted[3] = {2, 3, 4};
    for (int c = 0; c < 3; ++c) {
        const float tint = tints[c];
        EXPECT_NEAR(at(img, "beauty", 2, 8, c), tint * emitted[c], 1e-5f) << c;
        EXPECT_NEAR(at(img, "beauty", 13, 8, c), tint * 0.5f, 1e-6f) << c;
    }
}

TEST(Mirror, AnObjectHiddenFromReflectionsDisappearsFromTheMirrorOnly) {
    // A black card behind the camera, in front of the emitter.
    json card = {
        {"name", "card"}, {"type", "quad"}, {"material", "black"}, {"vertices", {{-50, -50, 8}, {-50, 50, 8}, {0, 50, 8}, {0, -50, 8}}}};
    EXPECT_EQ(at(render_image(test::scene_from(mirror_scene(card))), "beauty", 2, 8), 0.0f);
    card["visible_to"] = {{"reflections", false}};
    EXPECT_NEAR(at(render_image(test::scene_from(mirror_scene(card))), "beauty", 2, 8), 1.6f, 1e-5f);
}

TEST(Mirror, ANormalMapTiltsWhatTheMirrorShowsByTwiceItsAngle) {
    // A constant tangent-space normal map tilts the mirror's normal by 5 degrees towards -x
    // (the quad's dP/du is +x), so reflections turn 10 degrees: a pixel column whose mirror point
    // x_m satisfies x_m + 10 tan(atan(x_m / 5) - 10 deg) < 0 sees the emitter (x < 0 at z = 10).
    // That moves the edge from x_m = 0 (between columns 7 and 8) to x_m = 0.584: columns 8-12
    // (x_m up to 0.551) turn to the emitter, columns 14-15 (from 0.661) still show the sky.
    test::TempDir d;
    const float tilt = 5 * kPi / 180;
    const std::string map = d.file("tilt.exr");
    test::write_constant_image(map, 4, 4, {(1 - std::sin(tilt)) / 2, 0.5f, (1 + std::cos(tilt)) / 2});
    json j = mirror_scene();
    j["materials"]["mirror"]["normal_texture"] = map;
    const Image img = render_image(test::scene_from(j));
    const float tints[3] = {0.8f, 0.6f, 0.4f}, emitted[3] = {2, 3, 4};
    for (int c = 0; c < 3; ++c) {
        for (int x : {2, 8, 12}) EXPECT_NEAR(at(img, "beauty", x, 8, c), tints[c] * emitted[c], 1e-5f) << x;
        for (int x : {14, 15}) EXPECT_NEAR(at(img, "beauty", x, 8, c), tints[c] * 0.5f, 1e-6f) << x;
    }
    // Without the map, column 8 shows the sky (the untilted edge is at the image's centre).
    EXPECT_NEAR(at(render_image(test::scene_from(mirror_scene())), "beauty", 8, 8), 0.8f * 0.5f, 1e-6f);
}

TEST(Glass, ASlabShiftsTheRayByTheAnalyticDistance) {
    // A slab of thickness 1 and index 1.5 (faces at z = 0 and z = -1, normals outwards), a wall at z = -5.
    json j = {{"camera", {{"position", {-5, 0, 5}}, {"look_at", {0, 0, 0}}, {"resolution", {8, 8}}}},
              {"materials", {{"glass", {{"color", 0}, {"transmission", 1}, {"ior", 1.5}}}, {"wall", {{"color", 0.5}}}}},
              {"objects",
               {{{"name", "front"},
                 {"type", "quad"},
                 {"material", "glass"},
                 {"vertices", {{-50, -50, 0}, {50, -50, 0}, {50, 50, 0}, {-50, 50, 0}}}},
                {{"name", "back"},
                 {"type", "quad"},
                 {"material", "glass"},
                 {"vertices", {{-50, -50, -1}, {-50, 50, -1}, {50, 50, -1}, {50, -50, -1}}}},
                {{"name", "wall"},
                 {"type", "quad"},
                 {"material", "wall"},
                 {"vertices", {{-50, -50, -5}, {50, -50, -5}, {50, 50, -5}, {-50, 50, -5}}}}}}};
    const Scene s = test::scene_from(j);
    SceneAccel accel(s, s.render.lighting);
    DirectLighting lighting(s, accel, s.render.lighting);
    const Materials materials(s);
    const SpecularTracer tracer(s, accel, lighting, materials, s.render.shading.specular_depth);
    ASSERT_TRUE(tracer.active());
    Fragment f;
    f.p = f.p_base = {0, 0, 0}, f.n = f.ng = f.n_base = {0, 0, 1};
    f.material = 0, f.object = 0, f.prim = 0, f.weight = 1, f.footprint = 0.01f, f.depth = std::sqrt(50.0f);
    PixelPaths paths;
    Counters counters;
    tracer.trace(std::span<const Fragment>(&f, 1), s.camera.position, paths, counters);
    const PathSite* through = nullptr;
    for (const PathSite& site : paths.sites)
        if (site.kind == PathKind::Refraction && (!through || site.weight.x > through->weight.x)) through = &site;
    ASSERT_TRUE(through);
    // 45 degrees in: sin(t) = sin(45) / 1.5 inside; out parallel to the incoming ray.
    const float sin_t = std::sqrt(0.5f) / 1.5f, tan_t = sin_t / std::sqrt(1 - sin_t * sin_t);
    EXPECT_NEAR(through->at.p.x, tan_t + 4, 1e-4f);
    EXPECT_NEAR(through->at.p.z, -5, 1e-4f);
    // The perpendicular shift: t sin(i) (1 - cos(i) / (n cos(t))).
    const float shift = std::sqrt(0.5f) * (1 - std::sqrt(0.5f) / (1.5f * std::sqrt(1 - sin_t * sin_t)));
    EXPECT_NEAR((5 - through->at.p.x) * std::sqrt(0.5f), shift, 1e-4f);
    // In and out through two boundaries with the same Fresnel share (reciprocity).
    const float F = fresnel_dielectric(std::sqrt(0.5f), 1.5f);
    EXPECT_NEAR(through->weight.x, (1 - F) * (1 - F), 1e-5f);
    // The site's footprint is the camera pixel's cone over the whole path.
    EXPECT_NEAR(through->at.footprint, 0.01f * (1 + through->at.depth / f.depth), 1e-6f);
}

/// A sphere of glass (index 1.5) alone under a uniform sky of radiance 1.
json sphere_scene(const json& glass) {
    return {{"camera", {{"position", {0, 0, 10}}, {"look_at", {0, 0, 0}}, {"fov", 14}, {"resolution", {32, 32}}}},
            {"render", {{"gi", "none"}, {"spp", 4}}},
            {"materials", {{"glass", glass}}},
            {"lights", {{{"type", "sky"}, {"color", 1}}}},
            {"objects",
             {{{"name", "ball"},
               {"type", "sphere"},
               {"center", {0, 0, 0}},
               {"radius", 1},
               {"subdivisions", 5},
               {"fine_subdivisions", 1},
               {"material", "glass"}}}}};
}

TEST(Glass, ASphereReflectsTheFresnelShareAtNormalAndGrazingIncidence) {
    // Light that enters is absorbed: what is left is the surface's reflection of the sky.
    const Scene s = test::scene_from(sphere_scene({{"color", 0}, {"transmission", 1}, {"absorption", 1e4}}));
    // The rendered image at normal incidence (the centre pixels) and the sky around the ball.
    const Image img = render_image(s);
    EXPECT_NEAR(at(img, "beauty", 16, 16), 0.04f, 3e-4f);
    EXPECT_NEAR(at(img, "beauty", 0, 0), 1.0f, 1e-6f);
    // Fragments at chosen angles on the ball (one pixel of the image averages a range of them
    // near the rim): what their paths see is F(angle) of the sky, within the tessellated
    // surface's normal error (the coarse sphere's interpolated normals).
    SceneAccel accel(s, s.render.lighting);
    DirectLighting lighting(s, accel, s.render.lighting);
    const Materials materials(s);
    const SpecularTracer tracer(s, accel, lighting, materials, s.render.shading.specular_depth);
    for (float angle_deg : {0.0f, 30.0f, 60.0f, 75.0f, 85.0f}) {
        // The point of the unit ball seen at that angle of incidence from the camera at (0, 0, 10).
        float phi = 0;
        for (int i = 0; i < 60; ++i) {  // solve angle(phi) = angle by bisection-free fixed point
            const Vec3 p{std::sin(phi), 0, std::cos(phi)};
            const float inc = std::acos(std::clamp(-dot(normalize(p - s.camera.position), p), -1.0f, 1.0f));
            phi += (angle_deg * kPi / 180 - inc) * 0.5f;
        }
        Fragment f;
        f.p = f.p_base = f.n = f.ng = f.n_base = {std::sin(phi), 0, std::cos(phi)};
        f.weight = 1, f.footprint = 1e-3f, f.depth = length(f.p - s.camera.position);
        PixelPaths paths;
        Counters counters;
        tracer.trace(std::span<const Fragment>(&f, 1), s.camera.position, paths, counters);
        const float c = -dot(normalize(f.p - s.camera.position), f.n);
        EXPECT_NEAR(paths.seen_reflection[0].x, fresnel_dielectric(c, 1.5f), 0.015f * fresnel_dielectric(c, 1.5f)) << angle_deg;
        EXPECT_LT(paths.seen_refraction[0].x, 1e-6f) << angle_deg;
        EXPECT_EQ(paths.base[0].x, 0.0f);
    }
}

TEST(Glass, AClearSphereUnderAUniformSkyNeitherGainsNorLosesLight) {
    // Eight bounces: what light is still inside after them is lost (at most F^7 of it).
    const Scene s = test::scene_from(sphere_scene({{"color", 0.5}, {"transmission", 1}}), {"render.specular_depth=8"});
    const Image img = render_image(s);
    const CameraRays camera(s.camera);
    int checked = 0;
    for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 32; ++x) {
            if (at(img, "beauty", x, y, 3) < 1) continue;  // partly sky
            const Vec3 n = {at(img, "N", x, y, 0), at(img, "N", x, y, 1), at(img, "N", x, y, 2)};
            const float c = -dot(normalize(camera.direction(static_cast<float>(x) + 0.5f, static_cast<float>(y) + 0.5f)), n);
            // Near the rim light refracted in meets the far side close to the critical angle,
            // where the tessellation's normal error may trap some of it (docs/shading.md).
            EXPECT_NEAR(at(img, "beauty", x, y), 1.0f, c > 0.35f ? 2e-3f : 0.06f) << x << "," << y;
            checked += c > 0.35f;
        }
    EXPECT_GT(checked, 400);
    // Without specular bounces the clear sphere shows nothing (its base share is 0).
    const Image none = render_image(test::scene_from(sphere_scene({{"color", 0.5}, {"transmission", 1}}), {"render.specular_depth=0"}));
    EXPECT_EQ(at(none, "beauty", 16, 16), 0.0f);
}

TEST(Glass, AClearSphereNeedsNoRecordsAndATintedOneDoes) {
    // A clear sphere shows only what its paths bring: its own fragments gather nothing.
    Stats clear_stats, tinted_stats;
    render_image(test::scene_from(sphere_scene({{"color", 0.5}, {"transmission", 1}}), {"render.gi=cache"}), &clear_stats);
    render_image(test::scene_from(sphere_scene({{"color", 0.5}, {"transmission", 0.5}}), {"render.gi=cache"}), &tinted_stats);
    const json c = clear_stats.to_json(), t = tinted_stats.to_json();
    EXPECT_EQ(c["records"].get<double>(), 0);
    EXPECT_EQ(c["rays"]["gather"].get<double>(), 0);
    EXPECT_EQ(c["shading_misses"].get<double>(), 0);
    EXPECT_GT(t["records"].get<double>(), 0);
    EXPECT_EQ(t["shading_misses"].get<double>(), 0);
}

TEST(Glass, APileOfSheetsAtAGrazingAngleStopsAtTheRayBudget) {
    // Sixty sheets of glass seen at 80 degrees: every crossing splits a path in two (F ~ 0.43), and
    // between the sheets the reflected halves bounce on: 2^16 paths at 16 bounces unbounded.
    json j = {{"camera", {{"position", {0, 1.76, -10}}, {"look_at", {0, 0, 0}}, {"fov", 1}, {"resolution", {4, 4}}}},
              {"render", {{"gi", "none"}, {"spp", 1}, {"specular_depth", 16}}},
              {"materials", {{"glass", {{"color", 0}, {"transmission", 1}, {"ior", 3}}}}},
              {"lights", {{{"type", "sky"}, {"color", 1}}}},
              {"objects", json::array()}};
    for (int i = 0; i < 60; ++i) {
        const double y = -0.05 * i;
        j["objects"].push_back({{"name", "sheet" + std::to_string(i)},
                                {"type", "quad"},
                                {"material", "glass"},
                                {"vertices", {{-50, y, -50}, {-50, y, 50}, {50, y, 50}, {50, y, -50}}}});
    }
    Stats stats;
    render_image(test::scene_from(j), &stats);
    // One trace per pixel: without gathers the paths are traced by the shading pass alone.
    const double per_pixel = stats.to_json()["rays"]["specular"].get<double>() / 16;
    EXPECT_LE(per_pixel, kMaxRaysPerPixel);
    EXPECT_GT(per_pixel, kMaxRaysPerPixel / 2);  // the budget, not the weights, ended it
}

Scene mirror_glass(const std::vector<std::string>& extra) {
    std::vector<std::string> sets = {"camera.resolution=[48,48]", "render.spp=2", "render.rays=64"};
    sets.insert(sets.end(), extra.begin(), extra.end());
    return load_scene(test::source_dir() + "/scenes/cornell/mirror-glass.json", std::vector<Override>(sets.begin(), sets.end()));
}

TEST(MirrorGlassScene, TheGatheringPassCoversEverySiteAndTheCacheTracksBruteForce) {
    Stats cs, bs, rs;
    const Image cache = render_image(mirror_glass({"render.gi=cache"}), &cs);
    const Image brute = render_image(mirror_glass({"render.gi=brute"}), &bs);
    const Image rad = render_image(mirror_glass({"render.gi=cache", "render.indirect_at_specular_hits=radiosity"}), &rs);
    const json c = cs.to_json(), r = rs.to_json();
    EXPECT_EQ(c["shading_misses"].get<double>(), 0);
    EXPECT_GT(c["specular_sites"].get<double>(), 100);
    EXPECT_GT(c["specular_site_records"].get<double>(), 0);
    EXPECT_FALSE(r.contains("specular_site_records"));  // the radiosity textures light the sites
    EXPECT_EQ(r["shading_misses"].get<double>(), 0);
    // Mean beauty: cache and brute force agree within a few %, the radiosity textures leave
    // out the sites' bounce light (darker).
    const auto mean = [](const Image& img) {
        double s = 0;
        for (int y = 0; y < img.height; ++y)
            for (int x = 0; x < img.width; ++x) s += img.at(*img.find("beauty"), x, y)[1];
        return s / (img.width * img.height);
    };
    EXPECT_NEAR(mean(cache) / mean(brute), 1.0, 0.03);
    EXPECT_LT(mean(rad), mean(cache));
}

TEST(MirrorGlassScene, WithRadiosityAtSpecularHitsTheSitesAreLookedUpInTheTextures) {
    // What mirrors and glass show is the textures' value at their sites: it follows the textures'
    // lattice, while the fragments seen directly and their gathers stay close. (Until 2026-12-07
    // the sites were shaded with shadow rays, the textures made for them unread.)
    const auto layer_mean = [](const Image& img, const char* name) {
        const Layer& l = *img.find(name);
        double s = 0;
        for (int y = 0; y < img.height; ++y)
            for (int x = 0; x < img.width; ++x) s += img.at(l, x, y)[1];
        return s / (img.width * img.height);
    };
    const std::vector<std::string> rad = {"render.gi=cache", "render.indirect_at_specular_hits=radiosity", "render.layers=components"};
    std::vector<std::string> fine = rad, coarse = rad, direct = rad;  // fine: the default lattice, 1/128 of the diagonal
    coarse.push_back("render.radiosity_texel=300");                   // the box is 555 wide: a side's lattice a point or two
    direct.push_back("render.radiosity=false");                       // no textures: the sites get their direct light by shadow rays
    const Image f = render_image(mirror_glass(fine)), c = render_image(mirror_glass(coarse)), d = render_image(mirror_glass(direct));
    const double rf = layer_mean(f, "reflection"), rc = layer_mean(c, "reflection"), rd = layer_mean(d, "reflection");
    // The fine lattice holds the sites' direct light: near the shadow rays' answer (8 % below it
    // here: the lattice's bilinear lookup across the lit wall's falloff).
    EXPECT_NEAR(rf / rd, 1.0, 0.15) << rf << " " << rd;
    // The reflection changes with the lattice, far more than the noise between two renders.
    const Layer &lf = *f.find("reflection"), &lc = *c.find("reflection");
    size_t differ = 0, seen = 0;  // of the values a mirror or glass shows
    for (size_t i = 0; i < lf.data.size(); ++i) seen += lf.data[i] > 0, differ += lf.data[i] != lc.data[i];
    EXPECT_GT(seen, 100u);
    EXPECT_GT(differ, seen / 2) << seen;
    EXPECT_GT(std::abs(rc - rf) / rf, 0.04) << rf << " " << rc;
}

}  // namespace
}  // namespace bounce
