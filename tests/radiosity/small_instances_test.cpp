// Small instances lit at the hit (render.radiosity_small_instances = hit, issue 64): a
// placement none of whose triangles reaches a texel is never baked; a gather hit on it takes
// one light sample per light where it landed, keyed by the hit, so the same hit has the same
// value however it is reached; a shot's carry says every hit on it may have changed.
#include <gtest/gtest.h>

#include <limits>

#include "bounce/accel/accel.h"
#include "bounce/lighting/materials.h"
#include "bounce/radiosity/hit_rates.h"
#include "bounce/radiosity/radiosity.h"
#include "bounce/render/render.h"
#include "bounce/scene/changes.h"
#include "test_util.h"

namespace bounce {
namespace {

using nlohmann::json;

/// A floor under a point light (and, with `sky`, a sun and a sky), a ball prototype placed
/// small 24 times (a bed of red balls, `small_material` if given) before one large placement.
json forest(const std::string& mode, bool sky, const std::string& small_material = "") {
    json transforms = json::array({{{"scale", 2}, {"translate", {0, 0, 3}}}});
    for (int k = 0; k < 24; ++k) {
        transforms.push_back(
            {{"scale", 0.2}, {"rotate", {15.0 * k, 0, 1, 0}}, {"translate", {0.5 * (k % 6) - 1.25, 0, 0.5 * (k / 6) - 1}}});
        if (!small_material.empty()) transforms.back()["material"] = small_material;
    }
    json j = {
        {"camera", {{"position", {0, 1.2, -2.6}}, {"look_at", {0, 0.1, 0}}, {"fov", 40}, {"resolution", {48, 32}}}},
        {"render", {{"spp", 2}, {"light_samples", 1}, {"seed", 5}, {"rays", 64}, {"radiosity_small_instances", mode}}},
        {"materials", {{"white", {{"color", 0.7}}}, {"red", {{"color", {0.8, 0.2, 0.1}}}}, {"black", {{"color", 0}}}}},
        {"lights", {{{"type", "point"}, {"position", {1, 6, -2}}, {"color", 60}}}},
        {"objects",
         {{{"name", "floor"}, {"type", "quad"}, {"material", "white"}, {"vertices", {{-6, 0, -6}, {-6, 0, 6}, {6, 0, 6}, {6, 0, -6}}}},
          {{"name", "ball"},
           {"type", "sphere"},
           {"center", {0, 1, 0}},
           {"radius", 1},
           {"subdivisions", 2},
           {"fine_subdivisions", 0},
           {"material", "red"},
           {"prototype", true}},
          {{"name", "balls"}, {"instances", {{"of", "ball"}, {"transforms", transforms}}}}}}};
    if (sky)
        j["lights"] = {{{"type", "distant"}, {"direction", {-0.3, -1, 0.4}}, {"color", 2}}, {{"type", "sky"}, {"color", {0.3, 0.4, 0.6}}}};
    return j;
}

/// The textures of `s`, laid out and nothing baked, with what they read.
struct Textures {
    const Scene& s;
    SceneAccel accel{s, s.render.lighting};
    Materials materials{s};
    DirectLighting lighting{s, accel, s.render.lighting};
    RadiosityTextures rt = RadiosityTextures::lazy(s, materials, lighting, s.render.radiosity);
};

TEST(SmallInstances, AreNeverBakedAndEqualTheirLatticeAtItsPoints) {
    const Scene hit = test::scene_from(forest("hit", false)), lattice = test::scene_from(forest("lattice", false));
    const Textures h{hit}, l{lattice};
    size_t small = 0, compared = 0;
    for (uint32_t id = 0; id < hit.objects.size(); ++id) {
        const Object& o = hit.objects[id];
        EXPECT_FALSE(l.rt.object(id).lit_at_hit);
        if (!o.placed()) continue;
        // The floor is no instance and the large ball reaches texels: both keep their lattice.
        const bool tiny = o.instance && o.placement.largest_scale() < 1;
        ASSERT_EQ(h.rt.object(id).lit_at_hit, tiny) << o.name;
        if (!tiny) continue;
        ++small;
        Counters counters;
        for (uint32_t t = 0; t < o.coarse_mesh().triangle_count(); t += 7)
            for (const bool front : {true, false})
                for (const auto& [u, v] : {std::pair{0.0f, 0.0f}, std::pair{1.0f, 0.0f}, std::pair{0.0f, 1.0f}}) {
                    // A point light, one sample: the lattice's point is the light at the hit, bit for bit.
                    const Color a = h.rt.lookup(id, t, u, v, front, counters), b = l.rt.lookup(id, t, u, v, front, counters);
                    ASSERT_EQ(a, b) << o.name << " triangle " << t << (front ? " front" : " back") << " at " << u << ", " << v;
                    compared += luminance(a) > 0;
                }
        EXPECT_EQ(counters.hits_lit, 3u * 2u * ((o.coarse_mesh().triangle_count() + 6) / 7));
    }
    EXPECT_EQ(small, 24u);
    EXPECT_GT(compared, 300u);  // lit sides, not zeros
    EXPECT_EQ(h.rt.baked_sides(), 0u);
    EXPECT_EQ(h.rt.allocated_bytes(), 0u);
    EXPECT_GT(l.rt.baked_sides(), 0u);
    // Inside a triangle the hit has its own light, the same however often it is asked.
    Counters counters;
    const uint32_t id = 3;
    ASSERT_TRUE(h.rt.object(id).lit_at_hit);
    const Color once = h.rt.lookup(id, 5, 0.3f, 0.2f, true, counters);
    const Textures again{hit};
    EXPECT_EQ(again.rt.lookup(id, 5, 0.3f, 0.2f, true, counters), once);
    EXPECT_EQ(h.rt.brightest(), std::numeric_limits<float>::max());  // a mover may show any of it
    EXPECT_LT(l.rt.brightest(), 10.0f);
}

TEST(SmallInstances, SavedTexturesLoadBackAndARenderKeepingTheirLatticeBakesIt) {
    const Scene hit = test::scene_from(forest("hit", false)), lattice = test::scene_from(forest("lattice", false));
    const Textures h{hit};
    Counters counters;
    for (uint32_t t = 0; t < 40; ++t) h.rt.lookup(2, t, 0.2f, 0.3f, true, counters);  // the large ball's lattice
    (void)h.rt.lookup(3, 0, 0.2f, 0.3f, true, counters);                              // a small one's hit
    ASSERT_EQ(h.rt.baked_sides(), 40u);
    const test::TempDir dir;
    h.rt.save(dir.path());
    RadiosityTextures back;
    std::string why;
    ASSERT_TRUE(RadiosityTextures::load(dir.path(), hit, hit.render.radiosity, h.materials, h.lighting, back, why)) << why;
    EXPECT_EQ(back.baked_sides(), 40u);
    EXPECT_TRUE(back.object(3).lit_at_hit);
    EXPECT_EQ(back.object(2).front, h.rt.object(2).front);
    // Files written with small instances lit at the hit hold none of their points: a render that
    // keeps their lattices reads the rest and bakes theirs as its gathers need them.
    const Textures l{lattice};
    ASSERT_TRUE(RadiosityTextures::load(dir.path(), lattice, lattice.render.radiosity, l.materials, l.lighting, back, why)) << why;
    EXPECT_EQ(back.baked_sides(), 40u);
    EXPECT_FALSE(back.object(3).lit_at_hit);
    EXPECT_EQ(back.lookup(3, 0, 0.0f, 0.0f, true, counters), l.rt.lookup(3, 0, 0.0f, 0.0f, true, counters));
    EXPECT_EQ(back.baked_sides(), 41u);
}

TEST(SmallInstances, TheProbeCountsTheHitsAGatherWouldMake) {
    // Under a ceiling 1 above a floor, both 400 wide, a floor point's rays leave through the
    // gap (100 or more away) with a chance under 1e-4: every gather ray of the floor hits the
    // ceiling; none hits the floor; the upper half of the frame, looking at the sky, gathers nothing.
    json j = {{"camera", {{"position", {0, 0.5, 0}}, {"look_at", {0, 0.5, 5}}, {"fov", 40}, {"resolution", {64, 64}}}},
              {"lights", {{{"type", "sky"}, {"color", 1}}}},
              {"objects",
               {{{"name", "floor"}, {"type", "quad"}, {"vertices", {{-200, 0, -200}, {-200, 0, 200}, {200, 0, 200}, {200, 0, -200}}}},
                {{"name", "ceiling"}, {"type", "quad"}, {"vertices", {{-200, 1, -200}, {200, 1, -200}, {200, 1, 200}, {-200, 1, 200}}}}}}};
    const Scene s = test::scene_from(j);
    const SceneAccel accel(s, s.render.lighting);
    const HitProbe p = probe_gather_hits(s, accel, 64, 32);
    ASSERT_EQ(p.hits.size(), 2u);
    EXPECT_EQ(p.slots, 64.0 * 64 * 32);
    // The floor fills the lower half of the frame (the ceiling the upper): half the pixels
    // gather from the floor, all into the ceiling; the ceiling's own gathers go to the floor.
    EXPECT_NEAR(p.hits[1] / p.slots, 0.5, 0.01);
    EXPECT_NEAR(p.hits[0] / p.slots, 0.5, 0.01);
    EXPECT_NEAR((p.hits[0] + p.hits[1]) / p.slots, 1.0, 1e-3);
    EXPECT_DOUBLE_EQ(p.hits_at_most(0, p.slots), p.hits[0] + 3);
    j["objects"][1]["vertices"] = {{-200, 1, 100}, {200, 1, 100}, {200, 1, 200}, {-200, 1, 200}};  // only far ahead
    j["camera"]["look_at"] = {0, -5, 1};                                                           // down: the floor fills the frame
    const Scene open = test::scene_from(j);
    const SceneAccel open_accel(open, open.render.lighting);
    const HitProbe q = probe_gather_hits(open, open_accel, 64, 32);
    EXPECT_EQ(q.hits[0], 0.0);
    EXPECT_LT(q.hits[1] / q.slots, 1e-3);  // a sliver of sky 100 away
}

TEST(SmallInstances, AutoLightsAtTheHitWhatFewGathersReachAndKeepsTheLatticeOfWhatManyDo) {
    const Scene s = test::scene_from(forest("auto", false));
    const SceneAccel accel(s, s.render.lighting);
    const Materials materials(s);
    const DirectLighting lighting(s, accel, s.render.lighting);
    const HitProbe p = probe_gather_hits(s, accel);
    const uint32_t big = 2, small = 3;
    ASSERT_GT(p.hits[small], 0);
    // The bed's first ball: 320 triangles, one light sample: the hit wins below 3 x 1 x 320
    // hits at most, at a frame's pixel_gather_rays under 960 slots / (its hits + 3).
    const double crossing = 3.0 * 1 * static_cast<double>(s.objects[small].coarse_mesh().triangle_count()) * p.slots / (p.hits[small] + 3);
    for (const double factor : {0.5, 2.0}) {
        RadiositySettings settings = s.render.radiosity;
        settings.pixel_gather_rays = crossing * factor;
        const RadiosityTextures rt = RadiosityTextures::lazy(s, materials, lighting, settings);
        EXPECT_EQ(rt.object(small).lit_at_hit, factor < 1) << "at " << factor << " x the crossing";
        EXPECT_FALSE(rt.object(big).lit_at_hit);  // not small: it reaches texels
    }
    RadiositySettings none = s.render.radiosity;  // no gathers to weigh: lattices
    EXPECT_FALSE(RadiosityTextures::lazy(s, materials, lighting, none).object(small).lit_at_hit);
}

Image render_of(json j, int threads, Stats& stats) {
    j["render"]["threads"] = threads;
    j["render"]["gi"] = "cache";
    return render(test::scene_from(j), {}, stats, nullptr).image;
}

double mean(const Image& im, const char* name) {
    const Layer* layer = im.find(name);
    if (!layer) return -1;
    double sum = 0;
    for (float x : layer->data) sum += x;
    return sum / static_cast<double>(layer->data.size());
}

TEST(SmallInstances, RenderTheirLatticesLightWithoutBakingItAndTheSameOnAnyThreads) {
    Stats lattice_stats, one, two, none;
    const Image lattice = render_of(forest("lattice", true), 1, lattice_stats);
    const Image black = render_of(forest("lattice", true, "black"), 1, none);
    const Image hit = render_of(forest("hit", true), 1, one), hit2 = render_of(forest("hit", true), 2, two);
    EXPECT_EQ(test::differing_values(hit, hit2), 0u);  // keyed by the hit, not by who shaded it first
    const nlohmann::json a = lattice_stats.to_json(), b = one.to_json();
    EXPECT_EQ(a["hits_lit"].get<uint64_t>(), 0u);
    EXPECT_GT(b["hits_lit"].get<uint64_t>(), 1000u);
    EXPECT_LT(b["radiosity_sides_baked"].get<double>(), a["radiosity_sides_baked"].get<double>());
    // The same light: the lattice's linear blend over a triangle smaller than a texel against
    // one sample where the ray landed (the sun's exact, the sky's averaged by the gather), to a
    // tenth of all the light the balls send.
    const double ml = mean(lattice, "indirect"), mh = mean(hit, "indirect"), balls = ml - mean(black, "indirect");
    ASSERT_GT(balls, 0.03 * ml) << ml << " " << mh;
    EXPECT_NEAR(mh, ml, 0.1 * balls);
}

TEST(SmallInstances, AShotsCarrySaysEveryHitOnThemMayHaveChangedWhenTheLightDoes) {
    json j = forest("hit", false);
    j["animation"] = {{"fps", 24}, {"frames", {1, 3}}};
    const auto at = [&](double frame) {
        LoadOptions o;
        o.frame = frame;
        return load_scene_text(j.dump(), "shot.json", {}, o);
    };
    for (const bool keyed : {false, true}) {
        if (keyed) j["lights"][0]["color"] = {{"keys", {{1, 60}, {3, 30}}}};
        const Scene one = at(1), two = at(2);
        const Textures first{one};
        const SceneAccel accel(two, two.render.lighting);
        const Materials materials(two);
        const DirectLighting lighting(two, accel, two.render.lighting);
        const SceneChanges changes = scene_changes(one, two);
        std::vector<LightChange> changed;
        Stats stats;
        const RadiosityTextures carried =
            RadiosityTextures::carry(first.rt, two, materials, lighting, two.render.radiosity, changes, changed, stats);
        size_t every = 0;
        for (const LightChange& c : changed) {
            if (c.triangle != LightChange::kEveryTriangle) continue;
            ++every;
            EXPECT_TRUE(carried.object(c.object).lit_at_hit);
            EXPECT_EQ(c.delta, std::numeric_limits<float>::max());
            EXPECT_FALSE(c.bounds.empty());
        }
        EXPECT_EQ(every, keyed ? 24u : 0u) << (keyed ? "the light changed" : "nothing changed");
    }
}

}  // namespace
}  // namespace bounce
