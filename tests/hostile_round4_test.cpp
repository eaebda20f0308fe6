// Issue 50 B, the fourth hostile round: files and values that crashed bounce, destroyed an
// input or were accepted silently. Each exits 2 with the file and the place.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

#include "test_util.h"

namespace bounce {
namespace {

using nlohmann::json;

std::string render_cmd(const std::string& scene, const std::string& out) { return "render " + scene + " -o " + out + " -q --res 16x16"; }

/// Exit 2 with one line holding every one of `parts`.
void refused(const std::string& args, const std::vector<std::string>& parts) {
    std::string err;
    EXPECT_EQ(test::run_bounce(args, &err), 2) << args << " -> " << err;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
    for (const auto& p : parts) EXPECT_NE(err.find(p), std::string::npos) << args << " -> " << err << " lacks " << p;
}

const char* kPlyHeader =
    "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
    "element face 1\nproperty list uchar int vertex_indices\nend_header\n";

/// A scene of one PLY mesh `ply` (written as m.ply).
std::string ply_scene(const test::TempDir& d, const std::string& ply) {
    d.write("m.ply", ply);
    json j = test::base_scene();
    j["objects"] = {{{"type", "mesh"}, {"file", "m.ply"}}};
    d.write("s.json", j.dump());
    return d.file("s.json");
}

TEST(HostilePly, AsciiBodiesAreReadAgainstTheirHeader) {
    test::TempDir d;
    const std::string two_vertices =
        "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
        "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
    struct Case {
        std::string body;
        std::vector<std::string> expect;
    };
    const std::vector<Case> cases = {
        // The crash: the face's line is a third vertex (Assimp aborted, exit 134).
        {two_vertices + "0 0 0\n1 0 0\n0 1 0\n", {"m.ply", "line 12", "face 0", "3 values where its properties take 1"}},
        // Three vertices where two are declared, then the face.
        {two_vertices + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", {"m.ply", "line 12", "face 0"}},
        // A list count of 255 with three indices.
        {std::string(kPlyHeader) + "0 0 0\n1 0 0\n0 1 0\n255 0 1 2\n", {"m.ply", "line 13", "face 0", "fewer than its properties need"}},
        {std::string(kPlyHeader) + "0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n", {"m.ply", "line 13", "vertex index 7 outside the 3 vertices"}},
        {std::string(kPlyHeader) + "0 0 0\n1 0 nan\n0 1 0\n3 0 1 2\n", {"m.ply", "line 11", "'nan' is not a float"}},
        {std::string(kPlyHeader) + "0 0 0\n1 0 0\n0 1 0\n3 0 1.5 2\n", {"m.ply", "line 13", "'1.5' is not a int"}},
        {std::string(kPlyHeader) + "0 0 0\n1 0 0\n0 1 0\n-3 0 1 2\n", {"m.ply", "line 13", "not a list count"}},
        {std::string(kPlyHeader) + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n0 0 0\n", {"m.ply", "line 14", "data past the elements"}},
        {std::string(kPlyHeader) + "0 0 0\n1 0 0\n", {"m.ply", "line 12", "ends at vertex 2"}},
    };
    for (const Case& c : cases) refused(render_cmd(ply_scene(d, c.body), d.file("o.exr")), c.expect);
    // The same file, well formed, renders.
    EXPECT_EQ(test::run_bounce(render_cmd(ply_scene(d, std::string(kPlyHeader) + "0 0 0\n1 0 0\n\n0 0 1\n3 0 1 2\n"), d.file("o.exr"))), 0);
}

}  // namespace
}  // namespace bounce
