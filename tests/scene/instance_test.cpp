// Instances ("instances": {"of": prototype, "transforms": [...]}): placements render as the same
// geometry written out flat (bit for bit where the placement rounds nothing: identity, mirrors;
// to float rounding under any other), share one prototype's triangles and BVH, report their own
// object in hits, take overrides and light links by name, and hostile instancers are refused.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <functional>

#include "bounce/accel/accel.h"
#include "bounce/core/image.h"
#include "bounce/lighting/materials.h"
#include "bounce/radiosity/radiosity.h"
#include "bounce/render/render.h"
#include "bounce/scene/changes.h"
#include "bounce/scene/mesh_cache.h"
#include "gltf_strip.h"
#include "test_util.h"

namespace bounce {
namespace {

using nlohmann::json;

/// A floor and a back wall under a point light; a ball prototype (centre (2.5, 1, 0.5), so
/// that mirrors move it) and `extra` objects.
json room(const json& extra, const json& ball_keys = json::object()) {
    json ball = {{"name", "ball"},    {"type", "sphere"},       {"center", {2.5, 1, 0.5}}, {"radius", 1},
                 {"subdivisions", 2}, {"fine_subdivisions", 0}, {"material", "white"},     {"prototype", true}};
    ball.update(ball_keys);
    json j = {
        {"camera", {{"position", {0, 2, -9}}, {"look_at", {0, 1, 0}}, {"fov", 50}, {"resolution", {40, 30}}}},
        {"render", {{"spp", 2}, {"light_samples", 2}, {"seed", 3}, {"rays", 16}}},
        {"materials", {{"white", {{"color", 0.7}}}, {"red", {{"color", {0.7, 0.1, 0.1}}}}, {"blue", {{"color", {0.1, 0.2, 0.8}}}}}},
        {"lights", {{{"type", "point"}, {"position", {1, 5, -2}}, {"color", 40}}}},
        {"objects",
         {{{"name", "floor"}, {"type", "quad"}, {"material", "white"}, {"vertices", {{-8, 0, -8}, {-8, 0, 8}, {8, 0, 8}, {8, 0, -8}}}},
          {{"name", "back"}, {"type", "quad"}, {"material", "red"}, {"vertices", {{-8, 0, 4}, {-8, 8, 4}, {8, 8, 4}, {8, 0, 4}}}},
          ball}}};
    for (const json& o : extra) j["objects"].push_back(o);
    return j;
}

/// The instanced scene and the same placements written out as objects of their own, in the
/// order the loader gives instances (the first at the instancer's index, the rest after).
struct Pair {
    json instanced, flat;
};
Pair instanced_and_flat(const json& transforms) {
    Pair p{room(json::array({{{"name", "balls"}, {"instances", {{"of", "ball"}, {"transforms", transforms}}}}})), {}};
    json flat = json::array();
    for (size_t k = 0; k < transforms.size(); ++k) {
        json o = room(json::array())["objects"][2];
        o.erase("prototype");
        o["name"] = transforms[k].value("name", "balls/" + std::to_string(k));
        if (transforms[k].contains("material")) o["material"] = transforms[k]["material"];
        json t = transforms[k];
        t.erase("name"), t.erase("material");
        o["transform"] = t;
        flat.push_back(o);
    }
    p.flat = room(flat);
    return p;
}

Image render_with(const json& scene, const std::string& gi) {
    Stats stats;
    return render(test::scene_from(scene, {Override("render.gi=" + gi)}), {}, stats, nullptr).image;
}

const json kExact = json::array({json::object(),
                                 {{"scale", {-1, 1, 1}}, {"name", "mirrored"}},
                                 {{"scale", {1, 1, -1}}, {"material", "blue"}},
                                 {{"scale", {-1, 1, -1}}}});

TEST(Instances, RenderAsTheSameGeometryWrittenOutFlatBitForBit) {
    const Pair p = instanced_and_flat(kExact);
    for (const std::string gi : {"none", "brute", "cache"}) {
        const Image a = render_with(p.instanced, gi), b = render_with(p.flat, gi);
        EXPECT_EQ(test::differing_values(a, b), 0u) << "--gi " << gi;
        // Not vacuous: the balls are in the picture, the blue one too.
        const Layer* albedo = a.find("albedo");
        ASSERT_TRUE(albedo);
        size_t blue = 0;
        for (int y = 0; y < a.height; ++y)
            for (int x = 0; x < a.width; ++x) blue += a.at(*albedo, x, y)[2] > 0.5f * 0.8f && a.at(*albedo, x, y)[0] < 0.2f;
        EXPECT_GT(blue, 20u) << "--gi " << gi;
    }
}

// Issue 65: what holds of identity placements under a sun and a sky (docs/instancing.md): the
// flat scene bit for bit without indirect light; with it (the bake's random numbers are keyed
// by object index, equal here), a gather ray meeting the shared edge of two triangles may take
// the other in the prototype's BVH: one pixel of 1 200 differs at 40x30, the sums to 1e-5.
TEST(Instances, IdentityPlacementsUnderSunAndSkyAreTheFlatSceneBitForBitWithoutIndirectLight) {
    const json identity = json::array({json::object(), {{"scale", {-1, 1, 1}}, {"name", "mirrored"}}, {{"scale", {1, 1, -1}}}});
    Pair p = instanced_and_flat(identity);
    for (json* j : {&p.instanced, &p.flat})
        (*j)["lights"] = {{{"type", "distant"}, {"direction", {-0.3, -1, 0.4}}, {"color", 2}},
                          {{"type", "sky"}, {"color", {0.3, 0.4, 0.6}}}};
    for (const std::string gi : {"none", "brute", "cache"}) {
        const Image a = render_with(p.instanced, gi), b = render_with(p.flat, gi);
        const Layer *la = a.find("beauty"), *lb = b.find("beauty");
        ASSERT_TRUE(la && lb);
        double sa = 0, sb = 0;
        for (size_t i = 0; i < la->data.size(); ++i) sa += la->data[i], sb += lb->data[i];
        if (gi == "none")
            EXPECT_EQ(test::differing_values(a, b), 0u);
        else
            EXPECT_LE(test::differing_values(a, b), a.layers.size() * 3 * a.width * a.height / 300) << "--gi " << gi;
        EXPECT_NEAR(sa / sb, 1.0, 1e-5) << "--gi " << gi;
        EXPECT_GT(sb, 0) << "--gi " << gi;
    }
}

// Issue 65: an edge a whole number of texels long sat on the lattice level's step, so a
// placement that rounded it one ulp longer (a glTF GPU instance's float matrix against a node's)
// got a finer lattice and 4 % other bounce light.
TEST(Instances, AnEdgeOneUlpLongerKeepsItsRadiosityLevel) {
    for (const float texel : {0.25f, 0.1f, 1.0f / 3.0f, 0.35355338f})
        for (int n = 1; n < 40; ++n) {
            const float edge = static_cast<float>(n) * texel;
            const int level = radiosity_level(edge, texel, 64);
            EXPECT_EQ(radiosity_level(std::nextafter(edge, 2 * edge), texel, 64), level) << n << " texels of " << texel;
            EXPECT_EQ(radiosity_level(std::nextafter(edge, 0.0f), texel, 64), level) << n << " texels of " << texel;
            EXPECT_NEAR(level, n, 1) << n << " texels of " << texel;
        }
}

TEST(Instances, EveryPlacementsLatticeLevelsAreItsTrianglesOwnWhateverItsScale) {
    // A placement that cannot stretch an edge to a texel is laid out at level 1 without
    // measuring each triangle; every level must still be the one its triangle gives.
    const json transforms = json::array(
        {{{"scale", 0.05}}, {{"scale", 0.4}}, {{"scale", 2}}, {{"matrix", {0.02, 0.05, 0, 0, 0, 0.1, 0, 0, 0, 0, 0.03, 0, 0, 0, 0, 1}}}});
    const Scene s = test::scene_from(room(json::array({{{"name", "balls"}, {"instances", {{"of", "ball"}, {"transforms", transforms}}}}})));
    const SceneAccel accel(s, s.render.lighting);
    const Materials materials(s);
    const DirectLighting lighting(s, accel, s.render.lighting);
    const RadiosityTextures rt = RadiosityTextures::lazy(s, materials, lighting, s.render.radiosity);
    const float texel = s.size() / 128.0f;
    size_t ones = 0, finer = 0;
    for (uint32_t id = 3; id < 7; ++id) {
        const Object& o = s.objects[id];
        ASSERT_EQ(rt.object(id).level.size(), o.coarse_mesh().triangle_count());
        for (uint32_t t = 0; t < o.coarse_mesh().triangle_count(); ++t) {
            const auto [a, b, c] = triangle_vertices(o.coarse_mesh(), o.to_world(), t);
            const int want = radiosity_level(std::max({length(b - a), length(c - b), length(a - c)}), texel, 255);
            ASSERT_EQ(rt.object(id).level[t], want) << "placement " << id - 3 << ", triangle " << t;
            (want == 1 ? ones : finer) += 1;
        }
    }
    EXPECT_GT(ones, 2 * s.objects[3].coarse_mesh().triangle_count());  // the small placements
    EXPECT_GT(finer, 0u);                                              // and the large one
}

TEST(Instances, UnderAnyPlacementEqualTheFlatGeometryToFloatRounding) {
    // Rays meet a placed prototype in its own space: rotations and translations round there.
    const json moved = json::array({{{"rotate", {30, 0, 1, 0}}, {"translate", {-3, 0, 1}}},
                                    {{"scale", 0.5}, {"translate", {0.25, 0, -2}}},
                                    {{"matrix", {0, 0, 1, 0, 0, 1, 0, 0, -1, 0, 0, 0, 0, 0, 0, 1}}}});
    const Pair p = instanced_and_flat(moved);
    const Image a = render_with(p.instanced, "none"), b = render_with(p.flat, "none");
    for (const char* name : {"depth", "N", "direct"}) {
        const Layer *la = a.find(name), *lb = b.find(name);
        ASSERT_TRUE(la && lb) << name;
        // Where a ray grazes a silhouette or a faceted ball's terminator, rounding may send it
        // elsewhere (at 40x30, 14 pixels of direct light; misplaced balls would be hundreds).
        size_t off = 0;
        double sum_a = 0, sum_b = 0;
        for (size_t i = 0; i < la->data.size(); ++i) {
            off += std::abs(la->data[i] - lb->data[i]) > 1e-4f * std::max(1.0f, std::abs(lb->data[i]));
            sum_a += std::abs(la->data[i]), sum_b += std::abs(lb->data[i]);
        }
        EXPECT_LT(static_cast<double>(off), 0.03 * static_cast<double>(la->data.size())) << name;
        EXPECT_NEAR(sum_a / sum_b, 1.0, 1e-3) << name;
        EXPECT_GT(sum_b, 0) << name;
    }
}

TEST(Instances, TheSceneBoundsAreEveryPlacedVertexsBitForBitThoughInteriorPlacementsAreNotPlacedVertexByVertex) {
    // A forest of rotated, scaled balls (a coarse and a fine tessellation): only the placements
    // that can reach the union's surface place every vertex; the union is still exact.
    json transforms = json::array();
    uint64_t state = 7;
    const auto uniform = [&](double lo, double hi) {
        state = state * 6364136223846793005ULL + 1442695040888963407ULL;
        return lo + (hi - lo) * static_cast<double>(state >> 11) / 9007199254740992.0;
    };
    for (int k = 0; k < 400; ++k)
        transforms.push_back({{"rotate", {uniform(0, 360), uniform(-1, 1), 1, uniform(-1, 1)}},
                              {"scale", uniform(0.3, 1.7)},
                              {"translate", {(k % 20) * 1.3 - 12 + uniform(-0.4, 0.4), uniform(0, 0.5), (k / 20) * 1.1 - 10}}});
    const Scene scene = test::scene_from(
        room(json::array({{{"name", "forest"}, {"instances", {{"of", "ball"}, {"transforms", transforms}}}}}), {{"fine_subdivisions", 1}}));
    Bounds coarse, fine, others;
    size_t placements = 0, shortcut = 0;
    for (const Object& o : scene.objects) {
        if (!o.instance) {
            if (o.placed()) others.extend(o.coarse_bounds());
            if (o.placed() && o.has_fine()) fine.extend(o.visible_mesh_bounds());
            continue;
        }
        ++placements;
        Bounds own;
        for (const Vec3& v : o.local_coarse->positions) own.extend(o.placement.point(v));
        for (const Vec3& v : o.local_fine->positions) fine.extend(o.placement.point(v));
        coarse.extend(own);
        for (int a = 0; a < 3; ++a) {  // each placement's box holds its vertices
            EXPECT_LE(o.instance_bounds.lo[a], own.lo[a]);
            EXPECT_GE(o.instance_bounds.hi[a], own.hi[a]);
        }
        shortcut += std::memcmp(&own, &o.instance_bounds, sizeof(Bounds)) != 0;
    }
    ASSERT_EQ(placements, 400u);
    Bounds expected = others;
    expected.extend(coarse);
    const Bounds all = scene.bounds();
    EXPECT_EQ(std::memcmp(&all, &expected, sizeof(Bounds)), 0);
    expected.extend(fine);
    const Bounds visible = scene.visible_bounds();
    EXPECT_EQ(std::memcmp(&visible, &expected, sizeof(Bounds)), 0);
    EXPECT_GT(shortcut, 300u);  // the interior's placements kept a conservative box
}

TEST(Instances, ShareOnePrototypesTrianglesAndReportTheirOwnObjectInHits) {
    // A row of 50 balls along x, 3 units apart.
    json transforms = json::array();
    for (int k = 0; k < 50; ++k) transforms.push_back({{"translate", {3 * k, 0, 0}}});
    const Scene s = test::scene_from(room(json::array({{{"name", "row"}, {"instances", {{"of", "ball"}, {"transforms", transforms}}}}})));
    ASSERT_EQ(s.objects.size(), 3u + 50u);
    const Object& proto = s.objects[2];
    EXPECT_TRUE(proto.prototype);
    EXPECT_EQ(proto.coarse.triangle_count(), 0u);  // its triangles live only in the shared mesh
    for (size_t i = 3; i < s.objects.size(); ++i) {
        EXPECT_TRUE(s.objects[i].instance);
        EXPECT_EQ(s.objects[i].coarse.positions.size(), 0u);
        EXPECT_EQ(s.objects[i].local_coarse.get(), proto.local_coarse.get());
    }
    EXPECT_EQ(s.objects[3].name, "row/0");
    EXPECT_EQ(s.objects[52].name, "row/49");
    // Down onto ball k's top: its own object, at the sphere's top (an icosphere's vertex).
    const SceneAccel accel(s, s.render.lighting);
    for (int k : {0, 1, 17, 49}) {
        const Hit h = accel.fine().intersect({2.5f + 3.0f * static_cast<float>(k), 10, 0.5f}, {0, -1, 0}, 0, INFINITY);
        ASSERT_TRUE(h.valid()) << k;
        EXPECT_EQ(h.object, k == 0 ? 3u : static_cast<uint32_t>(3 + k)) << k;
        EXPECT_NEAR(h.t, 8.0f, 1e-3f) << k;
        const SurfacePoint sp = s.objects[h.object].coarse_point(h.prim, h.u, h.v);
        EXPECT_NEAR(sp.p.x, 2.5f + 3.0f * static_cast<float>(k), 1e-4f);
        EXPECT_NEAR(sp.p.y, 2.0f, 1e-4f);
    }
    // Between the balls: the floor.
    EXPECT_EQ(accel.fine().intersect({4, 10, 0.5f}, {0, -1, 0}, 0, INFINITY).object, 0u);
    EXPECT_NEAR(s.bounds().hi.x, 2.5f + 3 * 49 + 1, 1e-3f);
}

TEST(Instances, PlacementsOfEqualScaleShareTheirRadiosityLayoutAndBakeOnlyWhatIsHit) {
    const json transforms = json::array({{{"translate", {-3, 0, 0}}},
                                         {{"translate", {0, 0, 0}}, {"rotate", {40, 0, 1, 0}}},
                                         {{"translate", {3, 0, 0}}},
                                         {{"translate", {0, 0, 2}}, {"scale", 3}}});
    const Scene s = test::scene_from(room(json::array({{{"name", "balls"}, {"instances", {{"of", "ball"}, {"transforms", transforms}}}}})));
    const SceneAccel accel(s, s.render.lighting);
    const Materials materials(s);
    const DirectLighting lighting(s, accel, s.render.lighting);
    RadiosityTextures rt = RadiosityTextures::lazy(s, materials, lighting, s.render.radiosity);
    // Placements 0-2 (objects 3, 4, 5) have the same edge lengths: one layout; the scaled one its own.
    EXPECT_EQ(rt.object(3).level.shared(), rt.object(4).level.shared());
    EXPECT_EQ(rt.object(3).offset.shared(), rt.object(5).offset.shared());
    EXPECT_NE(rt.object(3).level.shared(), rt.object(6).level.shared());
    EXPECT_GT(rt.object(6).front.points(), rt.object(3).front.points());
    EXPECT_EQ(rt.object(2).level.size(), 0u);  // the prototype has none
    // Values only where a lookup baked: one page of one side.
    EXPECT_EQ(rt.allocated_bytes(), 0u);
    Counters counters;
    const Color c = rt.lookup(4, 7, 0.2f, 0.3f, true, counters);
    EXPECT_TRUE(isfinite(c));
    const size_t page = rt.object(4).front.allocated_bytes();
    EXPECT_GT(page, 0u);
    EXPECT_EQ(rt.allocated_bytes(), page);
    EXPECT_EQ(rt.baked_sides(), 1u);
}

TEST(Instances, BetweenTwoFramesAMovedPlacementIsRigidAndARecolouredOneANewSurface) {
    json transforms = json::array();
    for (int k = 0; k < 20; ++k) transforms.push_back({{"translate", {3 * k, 0, 0}}});
    const json was = room(json::array({{{"name", "row"}, {"instances", {{"of", "ball"}, {"transforms", transforms}}}}}));
    json now = was;
    now["objects"][3]["instances"]["transforms"][5]["translate"] = {15, 1, 0};
    now["objects"][3]["instances"]["transforms"][7]["material"] = "blue";
    const Scene before = test::scene_from(was), after = test::scene_from(now);
    const SceneChanges c = scene_changes(before, after);
    ASSERT_TRUE(c.comparable);
    EXPECT_FALSE(c.visible_geometry_same);
    ASSERT_EQ(c.objects.size(), after.objects.size());
    for (size_t i = 0; i < c.objects.size(); ++i) {
        const ObjectMotion::Kind expected = after.objects[i].name == "row/5"   ? ObjectMotion::Kind::Rigid
                                            : after.objects[i].name == "row/7" ? ObjectMotion::Kind::Deforming
                                                                               : ObjectMotion::Kind::Static;
        EXPECT_EQ(c.objects[i].kind, expected) << after.objects[i].name;
    }
    EXPECT_TRUE(scene_changes(before, test::scene_from(was)).visible_geometry_same);
}

TEST(Instances, TakeMaterialOverridesAndLightLinksByNameAndGlob) {
    const json transforms = json::array({{{"translate", {-3, 0, 0}}}, {{"translate", {0, 0, 0}}, {"material", "blue"}}});
    json j = room(json::array({{{"name", "balls"}, {"material", "red"}, {"instances", {{"of", "ball"}, {"transforms", transforms}}}}}));
    const Scene s = test::scene_from(j);
    const auto material = [&](const Object& o) { return s.materials[static_cast<size_t>(o.material_override)].name; };
    EXPECT_EQ(material(s.objects[3]), "red");   // the instancer's
    EXPECT_EQ(material(s.objects[4]), "blue");  // the entry's own
    EXPECT_EQ(s.objects[4].coarse_point(0, 0.2f, 0.2f).material, static_cast<uint32_t>(s.objects[4].material_override));
    // Unlinked from the light by glob: no direct light on either ball, the floor still lit.
    j["lights"][0]["light_link"] = {{"exclude", {"balls/*"}}};
    const Scene linked = test::scene_from(j);
    EXPECT_EQ(linked.lights[0].lit[3], 0);
    EXPECT_EQ(linked.lights[0].lit[4], 0);
    EXPECT_EQ(linked.lights[0].lit[0], 1);
    const Image img = render_with(j, "none");
    const Layer *direct = img.find("direct"), *albedo = img.find("albedo");
    size_t ball_pixels = 0;
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x)
            if (img.at(*albedo, x, y)[2] > 0.7f) {  // blue: the second ball
                ++ball_pixels;
                EXPECT_EQ(img.at(*direct, x, y)[2], 0.0f);
            }
    EXPECT_GT(ball_pixels, 10u);
    // A placement's own visibility over the instancer's: the blue ball hidden from the camera.
    j["objects"][3]["instances"]["transforms"][1]["visible_to"] = {{"camera", false}};
    const Image hidden = render_with(j, "none");
    size_t blue = 0;
    for (int y = 0; y < hidden.height; ++y)
        for (int x = 0; x < hidden.width; ++x) blue += hidden.at(*hidden.find("albedo"), x, y)[2] > 0.7f;
    EXPECT_EQ(blue, 0u);
    EXPECT_FALSE(test::scene_from(j).objects[4].visible_to.camera);
    EXPECT_TRUE(test::scene_from(j).objects[3].visible_to.camera);
}

/// How a glTF file places its unit cube three times: a copy of the mesh per node, one mesh the
/// three nodes share, or one node with EXT_mesh_gpu_instancing.
enum class Cubes { Copies, Shared, GpuInstanced };

/// A glTF file of a floor quad and a unit cube placed three times (translation, rotation about
/// y, scale each), as `how` says.
json cube_nodes(Cubes how) {
    const float h = std::sqrt(0.5f);
    const std::vector<std::array<float, 3>> at = {{0, 0, 0}, {2, 0, 0}, {-2, 0.5f, 1}}, scale = {{1, 1, 1}, {0.5f, 1, 0.5f}, {1, 1, 1}};
    const std::vector<std::array<float, 4>> turn = {{0, 0, 0, 1}, {0, 0, 0, 1}, {0, h, 0, h}};
    std::string b;
    test::put<float>(b, {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0, 0, 1, 1, 0, 1, 1, 1, 1, 0, 1, 1});  // 96 bytes
    test::put<uint16_t>(
        b, {0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4, 3, 7, 6, 3, 6, 2, 0, 4, 7, 0, 7, 3, 1, 2, 6, 1, 6, 5});  // 72
    test::put<float>(b, {-5, 0, -5, 5, 0, -5, 5, 0, 5, -5, 0, 5});                                                         // 48
    test::put<uint16_t>(b, {0, 2, 1, 0, 3, 2});                                                                            // 12
    for (const auto& t : at) test::put<float>(b, {t[0], t[1], t[2]});                                                      // 36 at 228
    for (const auto& q : turn) test::put<float>(b, {q[0], q[1], q[2], q[3]});                                              // 48 at 264
    for (const auto& k : scale) test::put<float>(b, {k[0], k[1], k[2]});                                                   // 36 at 312
    json g = {{"asset", {{"version", "2.0"}}}, {"scene", 0}};
    g["buffers"] = {{{"byteLength", b.size()}, {"uri", "data:application/octet-stream;base64," + test::base64(b)}}};
    const auto view = [](int offset, int length) { return json{{"buffer", 0}, {"byteOffset", offset}, {"byteLength", length}}; };
    g["bufferViews"] = {view(0, 96), view(96, 72), view(168, 48), view(216, 12), view(228, 36), view(264, 48), view(312, 36)};
    const auto vec = [](int index, const char* type) {
        return json{{"bufferView", index}, {"componentType", 5126}, {"count", 3}, {"type", type}};
    };
    g["accessors"] = {
        {{"bufferView", 0}, {"componentType", 5126}, {"count", 8}, {"type", "VEC3"}, {"min", {0, 0, 0}}, {"max", {1, 1, 1}}},
        {{"bufferView", 1}, {"componentType", 5123}, {"count", 36}, {"type", "SCALAR"}},
        {{"bufferView", 2}, {"componentType", 5126}, {"count", 4}, {"type", "VEC3"}, {"min", {-5, 0, -5}}, {"max", {5, 0, 5}}},
        {{"bufferView", 3}, {"componentType", 5123}, {"count", 6}, {"type", "SCALAR"}},
        vec(4, "VEC3"),
        vec(5, "VEC4"),
        vec(6, "VEC3")};
    const json cube = {{"primitives", {{{"attributes", {{"POSITION", 0}}}, {"indices", 1}}}}};
    const json floor = {{"primitives", {{{"attributes", {{"POSITION", 2}}}, {"indices", 3}}}}};
    g["meshes"] = how == Cubes::Copies ? json{cube, cube, cube, floor} : json{cube, floor, floor, floor};
    g["nodes"] = json::array();
    const int floor_mesh = how == Cubes::Copies ? 3 : 1;
    if (how == Cubes::GpuInstanced) {
        g["extensionsUsed"] = {"EXT_mesh_gpu_instancing"};
        g["nodes"].push_back(
            {{"name", "cubes"},
             {"mesh", 0},
             {"extensions", {{"EXT_mesh_gpu_instancing", {{"attributes", {{"TRANSLATION", 4}, {"ROTATION", 5}, {"SCALE", 6}}}}}}}});
    } else {
        for (int k = 0; k < 3; ++k)
            g["nodes"].push_back({{"name", "cube" + std::to_string(k)},
                                  {"mesh", how == Cubes::Shared ? 0 : k},
                                  {"translation", at[static_cast<size_t>(k)]},
                                  {"rotation", turn[static_cast<size_t>(k)]},
                                  {"scale", scale[static_cast<size_t>(k)]}});
    }
    g["nodes"].push_back({{"name", "floor"}, {"mesh", floor_mesh}});
    g["scenes"] = {{{"nodes", json::array()}}};
    for (size_t n = 0; n < g["nodes"].size(); ++n) g["scenes"][0]["nodes"].push_back(n);
    return g;
}

/// The room with the cubes' file as its only object (its name "set", lifted by 0.5).
json cubes_scene(const test::TempDir& d, Cubes how, const json& extra = json::object()) {
    const std::string name = how == Cubes::Copies ? "copies.gltf" : how == Cubes::Shared ? "shared.gltf" : "gpu.gltf";
    d.write(name, cube_nodes(how).dump());
    json o = {{"name", "set"}, {"file", d.file(name)}, {"transform", {{"translate", {0, 0.5, 0}}}}};
    o.update(extra);
    json j = room(json::array());
    j["objects"] = {o};
    return j;
}

/// The cubes' placements render as the file with a copy per node, to the rounding of a placed ray.
void expect_renders_as_copies(const json& scene, const json& copies) {
    const Image a = render_with(scene, "brute"), b = render_with(copies, "brute");
    const Layer *da = a.find("depth"), *db = b.find("depth");
    size_t off = 0;
    for (size_t i = 0; i < da->data.size(); ++i) off += std::abs(da->data[i] - db->data[i]) > 1e-4f * std::max(1.0f, db->data[i]);
    EXPECT_LT(off, da->data.size() / 100);
    const auto mean = [](const Layer& l) {
        double sum = 0;
        for (float v : l.data) sum += v;
        return sum / static_cast<double>(l.data.size());
    };
    EXPECT_NEAR(mean(*a.find("beauty")) / mean(*b.find("beauty")), 1.0, 2e-3);
}

TEST(Instances, AGltfsSharedMeshesLoadAsInstancesAndRenderAsItsCopies) {
    test::TempDir d;
    const Scene s = test::scene_from(cubes_scene(d, Cubes::Shared));
    ASSERT_EQ(s.objects.size(), 4u);  // the floor (used once), then the cube's three placements
    EXPECT_FALSE(s.objects[0].instance);
    EXPECT_EQ(s.objects[0].coarse.triangle_count(), 2u);
    for (size_t i = 1; i < 4; ++i) {
        EXPECT_TRUE(s.objects[i].instance);
        EXPECT_EQ(s.objects[i].local_coarse.get(), s.objects[1].local_coarse.get());
        EXPECT_EQ(s.objects[i].coarse_mesh().triangle_count(), 12u);
    }
    // Named by node, placed by the node's transform then the object's.
    EXPECT_EQ(s.objects[1].name.rfind("set/cube", 0), 0u) << s.objects[1].name;
    Bounds all;
    for (size_t i = 1; i < 4; ++i) all.extend(s.objects[i].coarse_bounds());
    EXPECT_NEAR(all.lo.x, -2, 1e-6f);
    EXPECT_NEAR(all.hi.x, 2.5f, 1e-6f);  // (the middle cube, at x = 2, is half as wide)
    EXPECT_NEAR(all.hi.y, 2, 1e-6f);
    EXPECT_EQ(test::scene_from(cubes_scene(d, Cubes::Copies)).objects.size(), 1u);  // nothing shared: one flat mesh, as before
    expect_renders_as_copies(cubes_scene(d, Cubes::Shared), cubes_scene(d, Cubes::Copies));
}

TEST(Instances, GltfGpuInstancesLoadAsInstancesAndFlattenWhereTheObjectCannotShare) {
    test::TempDir d;
    const Scene s = test::scene_from(cubes_scene(d, Cubes::GpuInstanced));
    ASSERT_EQ(s.objects.size(), 4u);
    for (size_t i = 1; i < 4; ++i) {
        EXPECT_TRUE(s.objects[i].instance);
        EXPECT_EQ(s.objects[i].name, "set/cubes/" + std::to_string(i - 1));
    }
    // The third instance turned a quarter about y: x in [-2, -1], z in [0, 1] (z = 1 - local x).
    EXPECT_NEAR(s.objects[3].coarse_bounds().lo.x, -2, 1e-5f);
    EXPECT_NEAR(s.objects[3].coarse_bounds().lo.z, 0, 1e-5f);
    EXPECT_NEAR(s.objects[3].coarse_bounds().lo.y, 1, 1e-5f);
    expect_renders_as_copies(cubes_scene(d, Cubes::GpuInstanced), cubes_scene(d, Cubes::Copies));
    // An object that cannot share (a prototype) holds every copy in its own mesh.
    json proto = cubes_scene(d, Cubes::GpuInstanced, {{"prototype", true}});
    EXPECT_EQ(test::scene_from(proto).objects[0].local_coarse->triangle_count(), 3u * 12 + 2);
}

// Issue 65: GPU instances against the same placements made by nodes, in the radiosity lattice:
// the quarter-turned cube's float matrix differs from the node's by an ulp (-1.19e-7 for 0),
// and with a texel that makes its faces' diagonals a whole number of texels, one of the two was
// laid out finer (4 % other bounce light on a face). Every placement's levels are now the same.
TEST(Instances, GltfGpuInstancesAreLaidOutInTheRadiosityLatticeAsTheSameNodes) {
    test::TempDir d;
    const auto levels = [&](Cubes how) {
        json j = cubes_scene(d, how, {{"material", "white"}});
        j["render"]["radiosity_texel"] = std::sqrt(2.0f) / 4;  // a face's diagonal: 4 texels
        const Scene s = test::scene_from(j);
        const SceneAccel accel(s, s.render.lighting);
        const Materials materials(s);
        const DirectLighting lighting(s, accel, s.render.lighting);
        const RadiosityTextures rt = RadiosityTextures::lazy(s, materials, lighting, s.render.radiosity);
        std::vector<std::vector<uint8_t>> out;
        for (uint32_t id = 0; id < s.objects.size(); ++id) out.push_back(rt.object(id).level.vec());
        return out;
    };
    const auto gpu = levels(Cubes::GpuInstanced), nodes = levels(Cubes::Shared);
    ASSERT_EQ(gpu.size(), nodes.size());
    for (size_t id = 0; id < gpu.size(); ++id) EXPECT_EQ(gpu[id], nodes[id]) << "object " << id;
    ASSERT_EQ(gpu[3].size(), 12u);  // the turned cube's triangles, each a diagonal of 4 texels
    for (const uint8_t level : gpu[3]) EXPECT_EQ(level, 4);
}

TEST(Instances, AGltfsPlacementsFromTheMeshCacheAreTheParsedOnes) {
    test::TempDir d, cache;
    for (Cubes how : {Cubes::Shared, Cubes::GpuInstanced}) {
        const Scene parsed = test::scene_from(cubes_scene(d, how));
        setenv("BOUNCE_MESH_CACHE", cache.path().c_str(), 1);
        const uint64_t hits = mesh_cache_counts().hits;
        const Scene miss = test::scene_from(cubes_scene(d, how)), hit = test::scene_from(cubes_scene(d, how));
        unsetenv("BOUNCE_MESH_CACHE");
        EXPECT_EQ(mesh_cache_counts().hits, hits + 1);
        for (const Scene* s : {&miss, &hit}) {
            ASSERT_EQ(s->objects.size(), parsed.objects.size());
            for (size_t i = 0; i < parsed.objects.size(); ++i) {
                const Object &a = s->objects[i], &b = parsed.objects[i];
                EXPECT_EQ(a.name, b.name);
                EXPECT_EQ(a.instance, b.instance);
                EXPECT_EQ(a.placement.m, b.placement.m) << a.name;
                EXPECT_EQ(a.coarse_mesh().positions.size(), b.coarse_mesh().positions.size());
                const Bounds ba = a.coarse_bounds(), bb = b.coarse_bounds();
                EXPECT_EQ(std::memcmp(&ba, &bb, sizeof(Bounds)), 0) << a.name;
            }
        }
    }
}

TEST(Instances, MalformedGpuInstancesAreRefusedWithTheirPlace) {
    test::TempDir d;
    const auto refused = [&](const std::function<void(json&)>& edit, const std::vector<std::string>& parts) {
        json g = cube_nodes(Cubes::GpuInstanced);
        edit(g);
        d.write("bad.gltf", g.dump());
        json j = room(json::array());
        j["objects"] = {{{"name", "set"}, {"file", d.file("bad.gltf")}}};
        test::expect_input_error([&] { test::scene_from(j); }, parts);
    };
    const std::string at = "/nodes/0/extensions/EXT_mesh_gpu_instancing";
    refused([](json& g) { g["accessors"][4]["count"] = 1000; }, {"bad.gltf", at + "/attributes/TRANSLATION", "do not fit"});
    refused([](json& g) { g["accessors"][5]["count"] = 2; }, {at + "/attributes", "different counts"});
    refused([](json& g) { g["accessors"][4]["count"] = uint64_t{1} << 62; }, {at + "/attributes/TRANSLATION", "do not fit"});
    refused([](json& g) { g["bufferViews"][4]["byteOffset"] = ~uint64_t{0} - 4; }, {at + "/attributes/TRANSLATION", "do not fit"});
    refused([](json& g) { g["accessors"][4]["count"] = "three"; }, {"bad.gltf", "malformed glTF where EXT_mesh_gpu_instancing reads it"});
    refused([](json& g) { g["accessors"][4]["componentType"] = 5123; }, {at + "/attributes/TRANSLATION", "floats"});
    refused([](json& g) { g["accessors"][6]["type"] = "VEC4"; }, {at + "/attributes/SCALE", "VEC3"});
    refused([](json& g) { g["nodes"][0]["extensions"]["EXT_mesh_gpu_instancing"]["attributes"] = json::object(); },
            {at + "/attributes", "none of"});
    refused([](json& g) { g["nodes"][0]["extensions"]["EXT_mesh_gpu_instancing"]["attributes"]["ROTATION"] = 99; },
            {at + "/attributes/ROTATION", "not an accessor"});
}

TEST(Instances, TheBundledOrchardLoadsAndRendersItsPlacements) {
    const Scene s = load_scene(test::source_dir() + "/scenes/instances/orchard.json", {Override("camera.resolution=[48,27]")});
    size_t instances = 0, prototypes = 0;
    for (const Object& o : s.objects) instances += o.instance, prototypes += o.prototype;
    EXPECT_EQ(instances, 404u);
    EXPECT_EQ(prototypes, 2u);
    Stats stats;
    const Image img = render(s, {}, stats, nullptr).image;
    // Every placement's triangles, counted once per placement; the autumn trees' override seen.
    EXPECT_EQ(stats.extra().value("instances", 0.0), 404.0);
    EXPECT_EQ(stats.extra().value("instanced_triangles", 0.0), 200.0 * (1280 + 10) + 4 * 1280);
    const Layer* albedo = img.find("albedo");
    size_t autumn = 0;
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x)
            autumn += std::abs(img.at(*albedo, x, y)[0] - 0.7f) < 1e-3f && std::abs(img.at(*albedo, x, y)[2] - 0.1f) < 1e-3f;
    EXPECT_GT(autumn, 5u);
}

TEST(Instances, HostileInstancersAreRefusedWithTheirPlace) {
    const auto instancer = [](const json& instances, const json& extra = json::object()) {
        json o = {{"name", "balls"}, {"instances", instances}};
        o.update(extra);
        return json::array({o});
    };
    const json one = json::array({{{"translate", {1, 0, 0}}}});
    const auto refused = [](const json& j, const std::vector<std::string>& parts) {
        test::expect_input_error([&] { test::scene_from(j); }, parts);
    };
    refused(room(instancer({{"of", "bal"}, {"transforms", one}})), {"/objects/3/instances/of", "no object is named \"bal\"", "\"ball\""});
    refused(room(instancer({{"of", "floor"}, {"transforms", one}})), {"/objects/3/instances/of", "not a prototype"});
    refused(room(instancer({{"of", "ball"}, {"transforms", json::array()}})), {"/objects/3/instances/transforms", "non-empty"});
    refused(room(instancer({{"of", "ball"}, {"transforms", json::array({1, 2})}})),
            {"/objects/3/instances/transforms/0", "transform object"});
    refused(room(instancer({{"of", "ball"}, {"transforms", json::array({{{"translate", {1, 0, 0}}, {"colour", 1}}})}})),
            {"/objects/3/instances/transforms/0", "colour"});
    refused(room(instancer({{"of", "ball"}, {"transforms", json::array({{{"translate", {1e39, 0, 0}}}})}})),
            {"/objects/3/instances/transforms/0/translate"});
    refused(room(instancer({{"of", "ball"}, {"transforms", json::array({{{"scale", 1e30}}})}})),
            {"/objects/3/instances/transforms/0", "beyond"});
    // Bounds are found in parallel; the first placement out of range is the one named.
    refused(room(instancer({{"of", "ball"}, {"transforms", json::array({json::object(), {{"scale", 1e30}}, {{"scale", -1e30}}})}})),
            {"/objects/3/instances/transforms/1", "beyond"});
    refused(room(instancer({{"of", "ball"}, {"transforms", json::array({{{"material", "gold"}}})}})),
            {"/objects/3/instances/transforms/0/material", "unknown material"});
    refused(room(instancer({{"of", "ball"}, {"transforms", one}}, {{"type", "sphere"}})), {"/objects/3", "type"});
    refused(room(instancer({{"of", "ball"}, {"transforms", one}, {"count", 3}})), {"/objects/3/instances", "count"});
    refused(room(json::array(), {{"fur", {{"density", 1}}}}), {"/objects/2", "prototype", "fur"});
    json lamp = room(json::array());
    lamp["materials"]["glow"] = {{"emission", 5}};
    lamp["objects"][2]["material"] = "glow";
    refused(lamp, {"/objects/2", "prototype", "emit light"});
    // Instances of an instancer.
    json nested = room(instancer({{"of", "ball"}, {"transforms", one}}));
    nested["objects"].push_back({{"name", "more"}, {"instances", {{"of", "balls"}, {"transforms", one}}}});
    refused(nested, {"/objects/4/instances/of", "not a prototype", "instances of instances"});
}

}  // namespace
}  // namespace bounce
