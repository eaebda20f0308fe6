// Fur: growing strands, hair fragments in the deep buffer, the cache at the root, hair shading.
#include <gtest/gtest.h>

#include <cmath>
#include <array>
#include <map>

#include "bounce/accel/accel.h"
#include "bounce/cache/passes.h"
#include "bounce/core/error.h"
#include "bounce/geometry/fur.h"
#include "bounce/render/render.h"
#include "test_util.h"

namespace bounce {
namespace {

using nlohmann::json;

/// A unit floor quad at y = 0 with fur under a uniform sky of radiance `sky`, seen at an angle.
json fur_scene(const json& fur, float sky = 1.0f) {
    json j = test::base_scene();
    j["camera"] = {{"position", {0, 0.8, 1.2}}, {"look_at", {0, 0, 0}}, {"fov", 50}, {"resolution", {40, 30}}};
    j["render"] = {{"spp", 4}, {"light_samples", 4}, {"rays", 64}};
    j["objects"] = json::array({{{"name", "lawn"},
                                 {"type", "quad"},
                                 {"vertices", {{-0.5, 0, -0.5}, {-0.5, 0, 0.5}, {0.5, 0, 0.5}, {0.5, 0, -0.5}}},
                                 {"fur", fur}}});
    j["lights"] = json::array({{{"type", "sky"}, {"color", sky}}});
    return j;
}

json plain_fur() { return {{"count", 4000}, {"length", 0.1}, {"width_root", 0.004}, {"width_tip", 0.002}, {"lean", 0.2}}; }

TEST(Fur, GrowingIsDeterministicAndStrandsStartOnTheSurface) {
    const TriangleMesh quad = make_quad({-1, 0, -1}, {-1, 0, 1}, {1, 0, 1}, {1, 0, -1}, 0);
    FurParams p;
    p.count = 500, p.length = 0.2f, p.length_variation = 0.25f, p.segments = 5, p.lean = 0;
    const Fur a = grow_fur(quad, p), b = grow_fur(quad, p);
    EXPECT_EQ(a.vertices, b.vertices);
    ASSERT_EQ(a.strand_count(), 500u);
    ASSERT_EQ(a.segment_count(), 2500u);
    p.seed = 2;
    EXPECT_NE(grow_fur(quad, p).vertices, a.vertices);
    for (size_t s = 0; s < a.strand_count(); ++s) {
        const float* v = &a.vertices[4 * 6 * s];
        // The root control point is the root; without lean or gravity the strand is straight up
        // the normal with a length within length x (1 +- variation).
        EXPECT_EQ(Vec3(v[0], v[1], v[2]), a.root_p[s]);
        EXPECT_FLOAT_EQ(a.root_p[s].y, 0.0f);
        EXPECT_NEAR(a.root_n[s].y, 1.0f, 1e-6f);
        const float len = v[4 * 5 + 1];
        EXPECT_GE(len, 0.15f - 1e-5f);
        EXPECT_LE(len, 0.25f + 1e-5f);
        EXPECT_NEAR(a.tangent(static_cast<uint32_t>(5 * s)).y, 1.0f, 1e-5f);
    }
    EXPECT_FLOAT_EQ(a.v_of(7, 0.5f), 2.5f / 5);  // segment 2 of strand 1
}

TEST(Fur, ClumpingDrawsTipsToTheGuideAndLeavesRootsInPlace) {
    const TriangleMesh quad = make_quad({-1, 0, -1}, {-1, 0, 1}, {1, 0, 1}, {1, 0, -1}, 0);
    FurParams p;
    p.count = 2000, p.segments = 2, p.lean = 0.6f, p.clump_size = 0.5f;
    const Fur loose = grow_fur(quad, p);
    p.clump = 1;
    const Fur tight = grow_fur(quad, p);
    // Fully clumped: every tip is its cell's guide's tip; roots never move.
    std::map<std::array<int, 3>, Vec3> guide_tip;
    size_t drawn = 0;
    for (size_t s = 0; s < tight.strand_count(); ++s) {
        const float* root = &tight.vertices[12 * s];
        EXPECT_EQ(Vec3(root[0], root[1], root[2]), loose.root_p[s]);
        const Vec3 c = tight.root_p[s] / 0.5f;
        const std::array<int, 3> cell{static_cast<int>(std::floor(c.x)), static_cast<int>(std::floor(c.y)),
                                      static_cast<int>(std::floor(c.z))};
        const Vec3 tip(root[8], root[9], root[10]);
        auto [it, fresh] = guide_tip.emplace(cell, tip);
        if (!fresh) {
            ++drawn;
            EXPECT_LT(length(tip - it->second), 1e-5f);
        }
    }
    EXPECT_EQ(guide_tip.size(), 16u);  // a 2 x 2 quad in cells of 0.5
    EXPECT_EQ(drawn, 2000u - 16u);
}

TEST(Fur, TheDensityMapThinsStrandsWhereItIsDark) {
    const TriangleMesh quad = make_quad({-1, 0, -1}, {1, 0, -1}, {1, 0, 1}, {-1, 0, 1}, 0);
    FurParams p;
    p.count = 4000;
    auto map = std::make_shared<UvMap>();
    map->width = 2, map->height = 1, map->values = {0.0f, 1.0f};  // u < 0.5 bare
    p.density_map = map;
    const Fur f = grow_fur(quad, p);
    for (const Vec2& uv : f.root_uv) EXPECT_GE(uv.x, 0.5f);
    // Half the area is bare: about half the strands remain (binomial, 6 sigma).
    EXPECT_NEAR(static_cast<double>(f.strand_count()), 2000.0, 6 * std::sqrt(1000.0));
}

TEST(Fur, KajiyaKayAndTheIndirectModelAreNormalisedAsDocumented) {
    // Under a uniform hemisphere of light, a Kajiya-Kay fibre (2/pi^2 albedo sin) reflects
    // albedo E / pi whatever its orientation: Monte Carlo for a lying strand (along x) under
    // the sky above (+y), against the model's diffuse term.
    double sum = 0;
    const int n = 200000;
    RandomStream rng(5, 0);
    for (int i = 0; i < n; ++i) {
        const float z = rng.get(static_cast<uint64_t>(i), 0), phi = 2 * kPi * rng.get(static_cast<uint64_t>(i), 1);
        const float r = std::sqrt(1 - z * z);
        const Vec3 w(r * std::cos(phi), z, r * std::sin(phi));  // uniform over the upper hemisphere
        sum += kajiya_kay(Vec3(1, 0, 0), w, Vec3(0, 0, 1), Color(1), 0, 1).x;
    }
    const double lying = sum / n * 2 * kPi;  // radiance under L = 1, so E = pi
    const Vec3 up(0, 1, 0), wo(0, 0, 1);
    EXPECT_NEAR(lying, 1.0, 5e-3);
    EXPECT_NEAR(hair_indirect(Vec3(1, 0, 0), up, up, wo, Color(kPi), Color(1), 0, 1).x, 1.0f, 1e-6f);
    EXPECT_NEAR(hair_indirect(up, up, up, wo, Color(kPi), Color(1), 0, 1).x, 1.0f, 1e-6f);
    // The specular part reads the pair as surfaces do: all of E / (n.d) from d.
    const Vec3 d = normalize(Vec3(0.6f, 0.8f, 0));
    const Color albedo(0.5f);
    EXPECT_NEAR(hair_indirect(Vec3(1, 0, 0), d, up, normalize(Vec3(-0.6f, 0.8f, 0)), Color(2), Color(0), 1, 10).x, 2 / 0.8f, 1e-4f);
    // Kajiya-Kay: diffuse (2/pi^2) albedo sin; the specular cone peaks where t.wo = -t.wi.
    const Vec3 wi = normalize(Vec3(0.6f, 0.8f, 0)), on_cone = normalize(Vec3(-0.6f, 0.8f, 0)), off = normalize(Vec3(0.6f, 0.8f, 0));
    const Color diffuse = kajiya_kay(Vec3(1, 0, 0), wi, on_cone, albedo, 0, 10);
    EXPECT_NEAR(diffuse.x, 0.5f * 0.8f * 2 / (kPi * kPi), 1e-6f);
    EXPECT_NEAR(kajiya_kay(Vec3(1, 0, 0), wi, on_cone, Color(0), 1, 10).x, 1.0f, 1e-5f);
    EXPECT_LT(kajiya_kay(Vec3(1, 0, 0), wi, off, Color(0), 1, 10).x, 0.01f);
    // The falloff runs from its root value to 1 at the tip.
    FurParams p;
    p.falloff_root = 0.25f, p.falloff_exponent = 2;
    EXPECT_FLOAT_EQ(p.falloff(0), 0.25f);
    EXPECT_FLOAT_EQ(p.falloff(0.5f), 0.25f + 0.75f * 0.25f);
    EXPECT_FLOAT_EQ(p.falloff(1), 1.0f);
}

TEST(Fur, HairFragmentsCarryTheirRootAndRoundTripThroughTheDeepFile) {
    Scene scene = test::scene_from(fur_scene(plain_fur()));
    Stats stats;
    SceneAccel accel(scene, scene.render.lighting);
    DeepBuffer deep = render_visibility(scene, accel, scene.render.visibility, stats, nullptr);
    const Fur& fur = *scene.objects[0].fur;
    size_t hair = 0;
    for (const Fragment& f : deep.fragments) {
        if (!f.is_hair()) continue;
        ++hair;
        EXPECT_NEAR(length(f.tangent), 1.0f, 1e-4f);
        EXPECT_GE(f.strand_v, 0.0f);
        EXPECT_LE(f.strand_v, 1.0f);
        ASSERT_LT(f.prim, fur.strand_count());
        EXPECT_EQ(f.p_base, fur.root_p[f.prim]);
        EXPECT_EQ(f.n_base, fur.root_n[f.prim]);
        // The hit lies on its strand: within the strand's length (+ width) of its root.
        EXPECT_LE(length(f.p - f.p_base), 0.1f * 1.2f + 0.01f);
        EXPECT_GT(f.p.y, -1e-5f);
    }
    EXPECT_GT(hair, deep.fragments.size() / 4);
    test::TempDir dir;
    write_deep(dir.file("fur.exr"), deep);
    EXPECT_EQ(read_deep(dir.file("fur.exr")), deep);
}

TEST(Fur, ADeepFileSurvivesFurShadingEditsButNotGrowthEdits) {
    const json fur = plain_fur();
    const uint64_t base = test::scene_from(fur_scene(fur)).visibility_fingerprint();
    for (const char* key : {"color_tip", "falloff_root", "cast_indirect", "indirect_at", "specular"}) {
        json f = fur;
        f[key] = std::string(key) == "cast_indirect" ? json(true) : std::string(key) == "indirect_at" ? json("fragment") : json(0.5);
        EXPECT_EQ(test::scene_from(fur_scene(f)).visibility_fingerprint(), base) << key;
    }
    for (const char* key : {"length", "width_root", "curl", "lean"}) {
        json f = fur;
        f[key] = 0.3;
        EXPECT_NE(test::scene_from(fur_scene(f)).visibility_fingerprint(), base) << key;
    }
}

/// A cache render of fur_scene(fur) under a sky of 0.5, and its shading pass's light per fragment.
struct HairRender {
    RenderResult result;
    std::vector<Indirect> indirect;
    double misses = 0;
};
HairRender render_hair(const json& fur) {
    Scene scene = test::scene_from(fur_scene(fur, 0.5f), {"render.gi=\"cache\""});
    Stats stats;
    HairRender h{render(scene, {}, stats, nullptr), {}, 0};
    InterpolatedLight light = interpolation_pass(scene, h.result.deep, *h.result.cache, test::still_plan(scene).tiling(), stats, nullptr);
    h.indirect = std::move(light.light);
    h.misses = static_cast<double>(light.misses);
    return h;
}

TEST(Fur, StrandsLookUpTheCacheAtTheRootAndShareOneValue) {
    // Hair invisible to gathers under a uniform sky: the root sees the open sky, E = pi L
    // exactly, for every hair fragment (records at the roots, no gradient along the strand).
    json fur = plain_fur();
    const HairRender open = render_hair(fur);
    std::map<uint32_t, Color> by_strand;
    size_t hair = 0;
    for (size_t i = 0; i < open.result.deep.fragments.size(); ++i) {
        const Fragment& f = open.result.deep.fragments[i];
        if (!f.is_hair()) continue;
        ++hair;
        EXPECT_NEAR(open.indirect[i].irradiance.x, kPi * 0.5f, 1e-4f);
        EXPECT_NEAR(open.indirect[i].ao, 1.0f, 1e-6f);
        auto [it, fresh] = by_strand.emplace(f.prim, open.indirect[i].irradiance);
        if (!fresh) {
            EXPECT_EQ(it->second, open.indirect[i].irradiance);  // exactly one value per strand
        }
    }
    EXPECT_GT(hair, 100u);
    EXPECT_EQ(open.misses, 0.0);

    // Seen by the gathers, the fur occludes its own roots: AO and E fall, and fragments of one
    // strand still share one value exactly.
    fur["cast_indirect"] = true;
    const HairRender occluded = render_hair(fur);
    std::map<uint32_t, Indirect> strands;
    double ao = 0;
    size_t n = 0, shared = 0;
    for (size_t i = 0; i < occluded.result.deep.fragments.size(); ++i) {
        const Fragment& f = occluded.result.deep.fragments[i];
        const Indirect& in = occluded.indirect[i];
        if (!f.is_hair()) continue;
        ao += in.ao, ++n;
        auto [it, fresh] = strands.emplace(f.prim, in);
        if (!fresh) {
            ++shared;
            EXPECT_EQ(it->second.irradiance, in.irradiance);
            EXPECT_EQ(it->second.ao, in.ao);
        }
    }
    ASSERT_GT(n, 100u);
    EXPECT_GT(shared, 10u);
    EXPECT_LT(ao / static_cast<double>(n), 0.97);
}

TEST(Fur, TheFalloffDarkensTheRootAndTheIndirectLayerFollowsIt) {
    json fur = plain_fur();
    fur["falloff_root"] = 0.2;
    Scene scene = test::scene_from(fur_scene(fur, 0.5f), {"render.gi=\"cache\"", "render.spp=1"});
    Stats stats;
    RenderResult r = render(scene, {}, stats, nullptr);
    const Layer& ind = *r.image.find("indirect");
    const FurParams& p = scene.objects[0].fur->params;
    size_t checked = 0;
    for (int y = 0; y < r.deep.height; ++y)
        for (int x = 0; x < r.deep.width; ++x) {
            auto frags = r.deep.pixel(x, y);
            if (frags.size() != 1 || !frags[0].is_hair()) continue;  // one sample: weight 1
            const float want = kPi * 0.5f * p.falloff(frags[0].strand_v);
            EXPECT_NEAR(ind.data[3 * (static_cast<size_t>(y) * r.deep.width + x)], want, 1e-4f * want + 1e-6f);
            ++checked;
        }
    EXPECT_GT(checked, 50u);
}

// Strands' shadows on the ground, with either name of the flag: fur_visibility_test.cpp.

TEST(Fur, ImagesDoNotDependOnThreadCount) {
    json fur = plain_fur();
    fur["curl"] = 0.2, fur["gravity"] = 0.3;
    std::vector<std::vector<float>> beauty;
    for (const char* threads : {"render.threads=1", "render.threads=2"}) {
        Stats s;
        RenderResult r = render(test::scene_from(fur_scene(fur), {"render.gi=\"cache\"", threads}), {}, s, nullptr);
        beauty.push_back(r.image.find("beauty")->data);
    }
    EXPECT_EQ(beauty[0], beauty[1]);
}

TEST(Fur, BadFurIsRefusedWithFileAndPlace) {
    auto expect_error = [](const json& fur, const std::string& where, const std::string& what) {
        try {
            test::scene_from(fur_scene(fur));
            ADD_FAILURE() << "no error for " << fur.dump();
        } catch (const InputError& e) {
            const std::string m = e.what();
            EXPECT_NE(m.find("inline.json"), std::string::npos) << m;
            EXPECT_NE(m.find(where), std::string::npos) << m;
            EXPECT_NE(m.find(what), std::string::npos) << m;
        }
    };
    json f = plain_fur();
    f["length"] = -0.1;
    expect_error(f, "/objects/0/fur/length", "");
    f = plain_fur();
    f["length"] = 1e39;
    expect_error(f, "/objects/0/fur/length", "");
    f = plain_fur();
    f["count"] = -5;
    expect_error(f, "/objects/0/fur/count", "");
    f = plain_fur();
    f.erase("count");
    f["density"] = 1e12;  // 1e12 strands on a unit quad
    expect_error(f, "/objects/0/fur/density", "");
    f["density"] = 1.5e9;  // fits the strand count, not the memory budget
    expect_error(f, "/objects/0/fur/density", "memory_budget");
    f = plain_fur();
    f["density_texture"] = "missing.png";
    expect_error(f, "/objects/0/fur/density_texture", "missing.png");
    f = plain_fur();
    f["density"] = 10;
    expect_error(f, "/objects/0/fur", "one of");
    f = plain_fur();
    f["segments"] = 0;
    expect_error(f, "/objects/0/fur/segments", "");
    f = plain_fur();
    f["colour_root"] = 1;
    expect_error(f, "/objects/0/fur/colour_root", "");
}

}  // namespace
}  // namespace bounce
