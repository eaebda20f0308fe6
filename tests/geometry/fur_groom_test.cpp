// Fur over a shot (issue 26): a mover's fur is grown once, as the object stands at the shot's
// first frame, and carried to every frame's pose strand for strand (geometry/fur.h, carry_fur),
// instead of being grown again on each pose, where area-weighted roots and world-space clump
// cells made strands jump from frame to frame.
#include <gtest/gtest.h>

#include <cmath>

#include "bounce/accel/accel.h"
#include "bounce/scene/scene_load.h"
#include "gltf_strip.h"
#include "test_util.h"

namespace bounce {
namespace {

using nlohmann::json;

Vec3 point(const Fur& fur, size_t k) { return {fur.vertices[4 * k], fur.vertices[4 * k + 1], fur.vertices[4 * k + 2]}; }

Scene load_at(const test::TempDir& dir, double frame) {
    LoadOptions o;
    o.frame = frame;
    return load_scene(dir.file("s.json"), {}, o);
}

TEST(FurGroom, ARigidMoversStrandsAreTheSameInItsOwnSpaceAtEveryFrame) {
    // A furry ball rolling (keyed translate and rotate) with clumping, lean, curl and gravity:
    // each of them depends on where the strand stands in the world when it is grown.
    test::TempDir dir;
    json j = test::base_scene();
    j["animation"] = {{"fps", 24}, {"frames", {1, 9}}};
    const json roll = {{"translate", {{"keys", {{1, {-2, 0.5, 0}}, {9, {2, 0.5, 1}}}}}},
                       {"rotate", {{"keys", {{1, {0, 0, 0, 1}}, {9, {-229, 0.3, 0, 1}}}}}}};
    j["objects"] = {{{"name", "ball"},
                     {"type", "sphere"},
                     {"radius", 0.5},
                     {"transform", roll},
                     {"fur",
                      {{"count", 600},
                       {"length", 0.3},
                       {"clump", 0.6},
                       {"clump_size", 0.1},
                       {"lean", 0.3},
                       {"curl", 0.1},
                       {"curl_turns", 2},
                       {"gravity", 0.5}}}}};
    dir.write("s.json", j.dump());
    const Scene first = load_at(dir, 1);
    const Fur& groom = *first.objects[0].fur;
    ASSERT_EQ(groom.strand_count(), 600u);
    const Transform to_first = first.objects[0].placement.inverse();
    for (double frame : {2.0, 4.5, 9.0}) {
        const Scene s = load_at(dir, frame);
        const Fur& fur = *s.objects[0].fur;
        ASSERT_EQ(fur.vertices.size(), groom.vertices.size()) << "frame " << frame;
        const Transform to_local = s.objects[0].placement.inverse();
        float worst = 0;
        for (size_t k = 0; k < fur.vertices.size() / 4; ++k)
            worst = std::max(worst, length(to_local.point(point(fur, k)) - to_first.point(point(groom, k))));
        EXPECT_LT(worst, 1e-5f) << "frame " << frame;  // the same strands, moved as the ball
        for (size_t s2 = 0; s2 < fur.strand_count(); ++s2) {
            EXPECT_EQ(fur.root_tri[s2], groom.root_tri[s2]);
            EXPECT_EQ(fur.root_bary[s2], groom.root_bary[s2]);
        }
    }
}

/// The skinned strip (tests/gltf_strip.h) with fur: its outer half folds about the elbow at
/// (1, 0, 0) by 90 degrees over frames 1 to 2; of its triangles, 0 and 1 stay, 2 turns rigidly
/// about the elbow, 3 stretches (at 45 degrees it folds flat, then turns over).
const json kClumpedFur = {{"count", 800}, {"length", 0.2}, {"width_root", 0.01}, {"width_tip", 0.01},
                          {"lean", 0.4},  {"clump", 0.5},  {"clump_size", 0.2}};
struct FurryStrip {
    test::TempDir dir;
    explicit FurryStrip(double shutter = 0, const json& fur = kClumpedFur) {
        dir.write("strip.gltf", test::skinned_strip().dump());
        json j = test::base_scene();
        j["animation"] = {{"fps", 1}, {"frames", {1, 2}}};
        if (shutter > 0) j["camera"]["shutter"] = {-shutter / 2, shutter / 2};
        j["objects"] = {{{"name", "strip"}, {"type", "mesh"}, {"file", "strip.gltf"}, {"animation", "bend"}, {"fur", fur}}};
        dir.write("s.json", j.dump());
    }
};

TEST(FurGroom, ASkinCarriesItsStrandsStrandForStrand) {
    const FurryStrip strip;
    const Scene first = load_at(strip.dir, 1);
    const Fur& groom = *first.objects[0].fur;
    ASSERT_EQ(groom.strand_count(), 800u);
    const size_t per = static_cast<size_t>(groom.segments) + 1;
    const Vec3 elbow(1, 0, 0);
    size_t turned = 0, still = 0;
    for (double frame : {1.25, 1.5, 2.0}) {
        const Scene s = load_at(strip.dir, frame);
        const Fur& fur = *s.objects[0].fur;
        ASSERT_EQ(fur.strand_count(), groom.strand_count()) << "frame " << frame;
        const float angle = static_cast<float>(kPi / 2 * (frame - 1));  // the elbow's turn about +z
        const float c = std::cos(angle), sn = std::sin(angle);
        for (size_t i = 0; i < fur.strand_count(); ++i) {
            ASSERT_EQ(fur.root_tri[i], groom.root_tri[i]);
            ASSERT_EQ(fur.root_bary[i], groom.root_bary[i]);
            const SurfacePoint sp = surface_point(s.objects[0].visible(), fur.root_tri[i], fur.root_bary[i].x, fur.root_bary[i].y);
            EXPECT_LT(length(fur.root_p[i] - sp.p), 1e-6f);  // rooted where the pose put its point
            for (size_t k = 0; k < per; ++k) {
                const Vec3 q = point(fur, i * per + k), g = point(groom, i * per + k);
                EXPECT_TRUE(isfinite(q));
                if (groom.root_tri[i] < 2) {  // on the half that stays: where it was
                    EXPECT_LT(length(q - g), 1e-6f);
                    ++still;
                } else if (groom.root_tri[i] == 2) {  // on the triangle that turns rigidly: turned with it
                    const Vec3 d = g - elbow;
                    EXPECT_LT(length(q - (elbow + Vec3(c * d.x - sn * d.y, sn * d.x + c * d.y, d.z))), 1e-5f);
                    ++turned;
                }
            }
            if (groom.root_tri[i] == 3) {  // stretched: the strand keeps its length
                for (size_t k = 0; k + 1 < per; ++k)
                    EXPECT_NEAR(length(point(fur, i * per + k + 1) - point(fur, i * per + k)),
                                length(point(groom, i * per + k + 1) - point(groom, i * per + k)), 1e-5f);
            }
        }
    }
    EXPECT_GT(still, 1000u);
    EXPECT_GT(turned, 500u);
}

TEST(FurGroom, ASkinsFurIsBlurredAsItsStrandsAreAtShutterOpenAndClose) {
    // Shutter half a frame about frame 1.5: the fur the camera sees at open and close is the
    // fur of frames 1.25 and 1.75 (the same strands, carried there), and its rays find it there.
    // Sparse thin strands, so that a short ray across one meets no other.
    const json fur = {{"count", 200}, {"length", 0.2}, {"width_root", 0.004}, {"width_tip", 0.004}, {"lean", 0}};
    const FurryStrip blurred(0.5, fur), sharp(0, fur);
    const Scene s = load_at(blurred.dir, 1.5);
    const Object& o = s.objects[0];
    ASSERT_FALSE(o.fur_shutter[0].empty());
    ASSERT_FALSE(o.fur_shutter[1].empty());
    const std::array<double, 2> at = {1.25, 1.75};
    for (size_t k = 0; k < 2; ++k) {
        const Scene at_then = load_at(sharp.dir, at[k]);
        const Fur& then = *at_then.objects[0].fur;
        ASSERT_EQ(o.fur_shutter[k].size(), then.vertices.size());
        float worst = 0;
        for (size_t i = 0; i < then.vertices.size(); ++i) worst = std::max(worst, std::abs(o.fur_shutter[k][i] - then.vertices[i]));
        EXPECT_LT(worst, 1e-5f) << "shutter " << (k ? "close" : "open");
    }
    // Per strand on the turning triangle, a ray across its middle (perpendicular to it and to its
    // motion about the elbow), at shutter open and close: hair where the strand was then, none
    // where it was at the other end.
    const SceneAccel accel(s, s.render.lighting);
    const Scene at_open = load_at(sharp.dir, 1.25), at_close = load_at(sharp.dir, 1.75);
    const Fur& open = *at_open.objects[0].fur;
    const Fur& close = *at_close.objects[0].fur;
    const size_t per = static_cast<size_t>(open.segments) + 1;
    const Vec3 elbow(1, 0, 0);
    auto meets = [&](const Fur& where, float time) {
        int n = 0;
        for (size_t i = 0; i < where.strand_count(); ++i) {
            if (where.root_tri[i] != 2) continue;
            const size_t mid = i * per + per / 2;
            const Vec3 m = point(where, mid), t = normalize(point(where, mid + 1) - point(where, mid - 1));
            const Vec3 d = normalize(cross(t, cross(Vec3(0, 0, 1), m - elbow)));
            const Hit h = accel.fine().intersect(m - d * 0.05f, d, 0, 0.1f, time, kRayCamera);
            n += h.valid() && h.hair && std::abs(h.t - 0.05f) < 0.01f;
        }
        return n;
    };
    int strands = 0;
    for (size_t i = 0; i < open.strand_count(); ++i) strands += open.root_tri[i] == 2;
    ASSERT_GE(strands, 30);
    EXPECT_GE(meets(open, 0), strands * 9 / 10);
    EXPECT_GE(meets(close, 1), strands * 9 / 10);
    EXPECT_LE(meets(open, 1), strands / 4);
    EXPECT_LE(meets(close, 0), strands / 4);
}

}  // namespace
}  // namespace bounce
