// Issue 26: glTF animation and skinning through Assimp, on a two-joint strip the test writes:
// posed at the frame's time, analytically; and a skin or animation that names what is not
// there exits 2 with the file and the place.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "bounce/core/error.h"
#include "gltf_strip.h"
#include "test_util.h"

namespace bounce {
namespace {

using nlohmann::json;
using test::skinned_strip;

/// A shot of 1 fps, frames 1-2 (1 second), looking at the strip playing `clip`.
json strip_scene(const std::string& clip) {
    json j = test::base_scene();
    j["animation"] = {{"fps", 1}, {"frames", {1, 2}}};
    j["camera"] = {{"position", {1, 0.5, 6}}, {"look_at", {1, 0.5, 0}}, {"fov", 40}, {"resolution", {16, 16}}};
    j["objects"] = {{{"name", "strip"}, {"type", "mesh"}, {"file", "strip.gltf"}, {"animation", clip}}};
    return j;
}

Bounds strip_at(const test::TempDir& d, double frame, const std::string& clip = "bend") {
    d.write("s.json", strip_scene(clip).dump());
    LoadOptions o;
    o.frame = frame;
    return load_scene(d.file("s.json"), {}, o).objects[0].coarse.bounds();
}

TEST(GltfAnimation, ASkinnedStripBendsAsItsJointTurns) {
    test::TempDir d;
    d.write("strip.gltf", skinned_strip().dump());
    const float h = std::sqrt(0.5f);
    // At rest the strip spans [0, 2] x [0, 1].
    Bounds b = strip_at(d, 1);
    EXPECT_NEAR(b.hi.x, 2, 1e-5);
    EXPECT_NEAR(b.hi.y, 1, 1e-5);
    // After a second the tip has turned 90 degrees about (1, 0, 0): (2, 0) -> (1, 1), (2, 1) -> (0, 1).
    b = strip_at(d, 2);
    EXPECT_NEAR(b.hi.x, 1, 1e-5);
    EXPECT_NEAR(b.lo.x, 0, 1e-5);
    EXPECT_NEAR(b.hi.y, 1, 1e-5);
    // Half way, 45 degrees: (2, 0) -> (1 + h, h), (2, 1) -> (1, 2h).
    b = strip_at(d, 1.5);
    EXPECT_NEAR(b.hi.x, 1 + h, 1e-4);
    EXPECT_NEAR(b.hi.y, 2 * h, 1e-4);
    d.write("s.json", strip_scene("bend").dump());
    LoadOptions o;
    o.frame = 1.5;
    const Scene s = load_scene(d.file("s.json"), {}, o);
    EXPECT_TRUE(s.objects[0].deforms);
    EXPECT_TRUE(s.objects[0].moves);
}

TEST(GltfAnimation, AClipThatIsNotThereOrAChannelOnAMissingNodeIsRefused) {
    test::TempDir d;
    d.write("strip.gltf", skinned_strip().dump());
    d.write("s.json", strip_scene("walk").dump());
    test::expect_refused("render " + d.file("s.json") + " -q -o " + d.file("o.exr"),
                         {"s.json", "/objects/0/animation", "no animation \"walk\"", "bend"});
    json g = skinned_strip();
    g["animations"][0]["channels"][0]["target"]["node"] = 7;
    d.write("strip.gltf", g.dump());
    d.write("s.json", strip_scene("bend").dump());
    test::expect_refused("render " + d.file("s.json") + " -q -o " + d.file("o.exr"),
                         {"strip.gltf", "/animations/0/channels/0/target/node", "not a node index"});
    g = skinned_strip(9);  // the tip names joint 9 of a two-joint skin
    d.write("strip.gltf", g.dump());
    test::expect_refused("render " + d.file("s.json") + " -q -o " + d.file("o.exr"), {"strip.gltf", "vertex 2", "no joint"});
    for (float w : {-1.0f, NAN}) {
        d.write("strip.gltf", skinned_strip(1, w).dump());
        std::string err;
        EXPECT_EQ(test::run_bounce("render " + d.file("s.json") + " -q -o " + d.file("o.exr"), &err), 2) << w;
        EXPECT_NE(err.find("strip.gltf"), std::string::npos) << err;
    }
}

}  // namespace
}  // namespace bounce
