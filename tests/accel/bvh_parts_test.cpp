// Issue 26, geometry over time: a shot's static set is built once, rigid movers are placed
// (Embree instances), deforming meshes are refit; and a frame traces as a fresh build would.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>

#include "bounce/accel/accel.h"
#include "bounce/core/random.h"
#include "bounce/scene/scene_load.h"
#include "gltf_strip.h"
#include "test_util.h"

namespace bounce {
namespace {

using nlohmann::json;

/// A floor (static), a ball rolling across it (keyed translate and rotate; a finer tessellation
/// for the camera), a second ball that gathers do not see, and the skinned strip bending
/// (deforming); `shutter` > 0: motion blur over that much of a frame.
struct Shot {
    test::TempDir dir;
    json scene = test::base_scene();
    explicit Shot(double shutter) {
        dir.write("strip.gltf", test::skinned_strip().dump());
        scene["animation"] = {{"fps", 1}, {"frames", {1, 2}}};
        scene["camera"] = {{"position", {0, 3, 8}}, {"look_at", {0, 0.5, 0}}, {"fov", 40}, {"resolution", {16, 16}}};
        if (shutter > 0) scene["camera"]["shutter"] = {-shutter / 2, shutter / 2};
        const json roll = {{"translate", {{"keys", {{1, {-2, 0.5, 0}}, {2, {2, 0.5, 0}}}}}},
                           {"rotate", {{"keys", {{1, {0, 0, 0, 1}}, {2, {-229, 0, 0, 1}}}}}}};
        const json hidden_roll = {{"translate", {{"keys", {{1, {-2, 0.5, 2}}, {2, {2, 0.5, 2}}}}}}};
        scene["objects"] = {
            {{"name", "floor"}, {"type", "quad"}, {"vertices", {{-6, 0, -6}, {-6, 0, 6}, {6, 0, 6}, {6, 0, -6}}}},
            {{"name", "ball"}, {"type", "sphere"}, {"radius", 0.5}, {"subdivisions", 2}, {"fine_subdivisions", 1}, {"transform", roll}},
            {{"name", "ghost"},
             {"type", "sphere"},
             {"radius", 0.5},
             {"subdivisions", 2},
             {"fine_subdivisions", 0},
             {"transform", hidden_roll},
             {"visible_to", {{"indirect", false}}}},
            {{"name", "strip"},
             {"type", "mesh"},
             {"file", "strip.gltf"},
             {"animation", "bend"},
             {"transform", {{"translate", {0, 0, -2}}}}}};
        dir.write("s.json", scene.dump());
    }
    Scene at(double frame) const {
        LoadOptions o;
        o.frame = frame;
        return load_scene(dir.file("s.json"), {}, o);
    }
};

bool same(const Hit& a, const Hit& b) {
    return a.object == b.object && a.prim == b.prim && a.hair == b.hair && std::bit_cast<uint32_t>(a.t) == std::bit_cast<uint32_t>(b.t) &&
           std::bit_cast<uint32_t>(a.u) == std::bit_cast<uint32_t>(b.u) && std::bit_cast<uint32_t>(a.v) == std::bit_cast<uint32_t>(b.v);
}

/// Rays from above the set towards it, in both BVHs of `a` and `b`: every hit the same, bit for
/// bit. Returns the hits per object of `a`'s coarse BVH (indirect rays).
std::vector<int> expect_same_hits(const SceneAccel& a, const SceneAccel& b, size_t objects) {
    std::vector<int> hits(objects, 0);
    for (uint32_t k = 0; k < 4000; ++k) {
        const Vec3 o(-4 + 8 * to_unit_float(mix64(4 * k)), 2.5f, -4 + 8 * to_unit_float(mix64(4 * k + 1)));
        const Vec3 target(-3 + 6 * to_unit_float(mix64(4 * k + 2)), 0.25f, -3 + 6 * to_unit_float(mix64(4 * k + 3)));
        const Vec3 d = normalize(target - o);
        const float time = to_unit_float(mix64(k + 99999));
        const Hit ha = a.coarse().intersect(o, d, 0, INFINITY, 0, kRayIndirect),
                  hb = b.coarse().intersect(o, d, 0, INFINITY, 0, kRayIndirect);
        EXPECT_TRUE(same(ha, hb)) << "coarse ray " << k;
        const Hit fa = a.fine().intersect(o, d, 0, INFINITY, time, kRayCamera),
                  fb = b.fine().intersect(o, d, 0, INFINITY, time, kRayCamera);
        EXPECT_TRUE(same(fa, fb)) << "fine ray " << k;
        if (ha.valid()) ++hits[ha.object];
    }
    return hits;
}

TEST(BvhParts, AShotsNextFrameTakesOverTheStaticSetPlacesRigidMoversRefitsSkinsAndTracesAsAFreshBuild) {
    for (double shutter : {0.0, 0.5}) {
        SCOPED_TRACE(shutter);
        const Shot shot(shutter);
        const Scene first = shot.at(1), next = shot.at(1.5);
        const SceneAccel a(first, first.render.lighting);
        // Parts: the static floor (coarse and camera alike); each ball's shape before its
        // placement (the ball's finer one for the camera too); the strip (and its shutter poses).
        const int strip_parts = shutter > 0 ? 2 : 1;
        EXPECT_EQ(a.reuse().built, 1 + 2 + 1 + strip_parts);
        const SceneAccel b(next, next.render.lighting, &a), fresh(next, next.render.lighting);
        EXPECT_EQ(b.reuse().kept, 1 + 2 + 1);
        EXPECT_EQ(b.reuse().refit, strip_parts);
        EXPECT_EQ(b.reuse().built, 0);
        EXPECT_FALSE(a.current());  // its strip part now holds frame 1.5
        EXPECT_TRUE(b.current());
        // The ray offset comes from the rolling ball's fine/coarse gap, measured before its
        // placement: the same at every frame, to the bit (measured where it is, rounding moved it).
        EXPECT_GT(a.ray_offset(), 1e-4f * first.size());
        EXPECT_EQ(a.ray_offset(), b.ray_offset());
        const Scene later = shot.at(1.9);
        EXPECT_EQ(a.ray_offset(), SceneAccel(later, later.render.lighting).ray_offset());
        const std::vector<int> hits = expect_same_hits(b, fresh, next.objects.size());
        EXPECT_GT(hits[0], 1000);
        EXPECT_GT(hits[1], 20);
        EXPECT_EQ(hits[2], 0);  // the ghost is not seen by gathers, whatever its placement
        EXPECT_GT(hits[3], 5);
        // Where the parts are at frame 1.5: the ball's top at (0, 1, 0), the ghost's seen by shadows.
        const Hit top = b.coarse().intersect({0, 3, 0}, {0, -1, 0}, 0, INFINITY, 0, kRayIndirect);
        EXPECT_EQ(top.object, 1u);
        EXPECT_NEAR(top.t, 2.0f, 0.02f);
        const Hit ghost = b.coarse().intersect({0, 3, 2}, {0, -1, 0}, 0, INFINITY, 0, kRayShadow);
        EXPECT_EQ(ghost.object, 2u);
        EXPECT_NEAR(ghost.t, 2.0f, 0.02f);
        // The strip's tip joint (at x = 1) has turned 45 degrees about z: its corners (2, 0) and
        // (2, 1) went to (1 + c, c) and (1, 2c), c = cos 45; aim at the centre of that triangle.
        const float c = std::sqrt(0.5f);
        const Hit tip = b.coarse().intersect({(3 + c) / 3, c, 3}, {0, 0, -1}, 0, INFINITY, 0, kRayIndirect);
        EXPECT_EQ(tip.object, 3u);
        EXPECT_NEAR(tip.t, 5.0f, 1e-4f);
    }
}

TEST(BvhParts, AStillHasOneBvhOfEverythingAndAFrameWhoseSkinWasRefitLaterIsNotKept) {
    const Shot shot(0);
    json still = shot.scene;
    still.erase("animation");
    for (json& o : still["objects"]) o.erase("animation"), o["transform"] = {{"translate", {0, 0, 0}}};
    shot.dir.write("still.json", still.dump());
    const Scene flat_scene = load_scene(shot.dir.file("still.json"));
    const SceneAccel flat(flat_scene, flat_scene.render.lighting);
    EXPECT_EQ(flat.reuse().built, 0);  // no parts
    EXPECT_TRUE(flat.current());
    // Frames 1, 2, then 1 again from frame 1's BVHs (the tool going back): frame 1's strip part
    // was refit to frame 2, so nothing of frame 1's is taken over as it was.
    const Scene one = shot.at(1), two = shot.at(2);
    const SceneAccel a(one, one.render.lighting), b(two, two.render.lighting, &a);
    EXPECT_FALSE(a.current());
    const SceneAccel again(one, one.render.lighting, &a), fresh(one, one.render.lighting);
    EXPECT_EQ(again.reuse().refit, 0);
    expect_same_hits(again, fresh, one.objects.size());
}

TEST(BvhParts, FurPartsAreNotTakenOverByAScenesWithOtherObjects) {
    // Fur's geometry ids follow the objects (mesh ids first): a lawn's fur part made for two
    // objects would name another object among three.
    test::TempDir dir;
    json j = test::base_scene();
    j["animation"] = {{"fps", 24}, {"frames", {1, 2}}};
    j["camera"] = {{"position", {0, 3, 3}}, {"look_at", {0, 0, 0}}, {"resolution", {16, 16}}};
    const json lawn = {{"name", "lawn"},
                       {"type", "quad"},
                       {"vertices", {{-0.5, 0, -0.5}, {-0.5, 0, 0.5}, {0.5, 0, 0.5}, {0.5, 0, -0.5}}},
                       {"fur", {{"count", 3000}, {"length", 0.1}, {"width_root", 0.004}, {"width_tip", 0.002}}}};
    const json ball = {{"name", "ball"},
                       {"type", "sphere"},
                       {"radius", 0.2},
                       {"transform", {{"translate", {{"keys", {{1, {-2, 0.5, 0}}, {2, {2, 0.5, 0}}}}}}}}};
    j["objects"] = {lawn, ball};
    dir.write("two.json", j.dump());
    j["objects"].push_back({{"name", "wall"}, {"type", "quad"}, {"vertices", {{-3, 0, -3}, {3, 0, -3}, {3, 2, -3}, {-3, 2, -3}}}});
    dir.write("three.json", j.dump());
    const Scene two = load_scene(dir.file("two.json")), three = load_scene(dir.file("three.json"));
    const SceneAccel a(two, two.render.lighting), b(three, three.render.lighting, &a);
    int hair = 0, wrong = 0;
    for (uint32_t k = 0; k < 200; ++k) {
        // Across the lawn, low: through a metre of strands.
        const Vec3 o(-1, 0.01f + 0.05f * to_unit_float(mix64(2 * k)), -0.4f + 0.8f * to_unit_float(mix64(2 * k + 1)));
        const Hit h = b.fine().intersect(o, {1, 0, 0}, 0, INFINITY, 0.5f, kRayCamera);
        hair += h.valid() && h.hair && h.object == 0;
        wrong += h.valid() && !(h.hair && h.object == 0);
    }
    EXPECT_GT(hair, 180);
    EXPECT_EQ(wrong, 0);
}

TEST(BvhParts, FurOnARigidMoverIsBlurredWithIt) {
    // A furry ball crossing 4 units a frame, the shutter open a whole frame about frame 1.5: the
    // camera sees each strand 2 units back at shutter open, where it is at the frame's time halfway,
    // 2 units on at close; shadows and gathers see the strands at the frame's time.
    test::TempDir dir;
    json j = test::base_scene();
    j["animation"] = {{"fps", 24}, {"frames", {1, 2}}};
    j["camera"] = {{"position", {0, 3, 8}}, {"look_at", {0, 0.5, 0}}, {"resolution", {16, 16}}, {"shutter", {-0.5, 0.5}}};
    j["objects"] = {{{"name", "ball"},
                     {"type", "sphere"},
                     {"radius", 0.5},
                     {"transform", {{"translate", {{"keys", {{1, {-2, 0.5, 0}}, {2, {2, 0.5, 0}}}}}}}},
                     {"fur", {{"count", 40}, {"length", 0.4}, {"width_root", 0.03}, {"width_tip", 0.03}, {"lean", 0}}}}};
    dir.write("s.json", j.dump());
    LoadOptions o;
    o.frame = 1.5;
    const Scene scene = load_scene(dir.file("s.json"), {}, o);
    const SceneAccel accel(scene, scene.render.lighting);
    const Fur& fur = *scene.objects[0].fur;
    const Vec3 x(1, 0, 0);
    // Per strand, a ray across its middle (perpendicular to it and to the motion), 1 unit long,
    // at a time and an offset along the motion: does it meet hair about where the strand would be?
    auto meets = [&](float time, float shift, bool camera) {
        int n = 0;
        for (size_t s = 0; s < fur.strand_count(); ++s) {
            const size_t first = s * static_cast<size_t>(fur.segments + 1);
            const size_t mid = first + static_cast<size_t>(fur.segments / 2);
            auto point = [&](size_t k) { return Vec3(fur.vertices[4 * k], fur.vertices[4 * k + 1], fur.vertices[4 * k + 2]); };
            const Vec3 m = point(mid), t = normalize(point(mid + 1) - point(mid - 1)), d = normalize(cross(t, x));
            const Vec3 target = m + x * shift;
            if (!camera) {  // shadow rays: anything across the segment
                n += accel.occluded(target - d, d, 2.0f, 0, kRayShadow);
                continue;
            }
            const Hit h = accel.fine().intersect(target - d, d, 0, 2, time, kRayCamera);
            n += h.valid() && h.hair && std::abs(h.t - 1) < 0.05f;
        }
        return n;
    };
    const int strands = static_cast<int>(fur.strand_count());
    ASSERT_GE(strands, 30);
    EXPECT_GE(meets(0.5f, 0, true), strands * 9 / 10);   // halfway: where the strands are
    EXPECT_GE(meets(0.0f, -2, true), strands * 9 / 10);  // open: 2 units back
    EXPECT_GE(meets(1.0f, 2, true), strands * 9 / 10);   // close: 2 units on
    EXPECT_LE(meets(0.0f, 0, true), strands / 10);       // not where they are at the frame's time
    EXPECT_LE(meets(1.0f, -2, true), strands / 10);
    EXPECT_GE(meets(0, 0, false), strands * 9 / 10);  // shadows: at the frame's time
    EXPECT_LE(meets(0, -2, false), strands / 10);
}

}  // namespace
}  // namespace bounce
