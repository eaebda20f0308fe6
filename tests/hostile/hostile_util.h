// What the hostile-input tests share: small scenes and files to attack, and the commands
// that render them (tests/hostile/, grouped by the surface they attack).
#pragma once

#include <OpenImageIO/deepdata.h>
#include <OpenImageIO/imageio.h>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <gtest/gtest.h>
#include <signal.h>
#include <string>
#include <sys/stat.h>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>
#include <vector>

#include "bounce/accel/accel.h"
#include "bounce/cache/cache_file.h"
#include "bounce/core/error.h"
#include "bounce/core/image.h"
#include "bounce/lighting/lighting.h"
#include "bounce/render/render.h"
#include "bounce/scene/scene_load.h"
#include "gltf_strip.h"
#include "test_util.h"

namespace bounce::hostile {

using nlohmann::json;
namespace fs = std::filesystem;
using test::expect_refused;
using test::write_constant_image;

/// A config whose view reads a 1D LUT (`thelut.cube` beside it, in luts/).
inline void write_lut_config(const test::TempDir& d) {
    std::string config = test::bytes_of(test::source_dir() + "/tests/data/ocio/config.ocio");
    config.replace(config.find("search_path: \"\""), 15, "search_path: luts");
    config += R"(
  - !<ColorSpace>
    name: lut
    family: ""
    equalitygroup: ""
    bitdepth: 32f
    isdata: false
    from_scene_reference: !<FileTransform> {src: thelut.cube, interpolation: linear}
)";
    config.replace(config.find("    - !<View> {name: raw, colorspace: linear}"), 0, "    - !<View> {name: lut, colorspace: lut}\n");
    d.write("lut.ocio", config);
    fs::create_directories(d.path() / "luts");
    d.write("luts/thelut.cube", "LUT_1D_SIZE 2\n0 0 0\n1 1 1\n");
}

inline std::string small_render(const test::TempDir& d) {
    d.write("s.json", test::base_scene().dump());
    return "render " + d.file("s.json") + " -q --threads 1 -o " + d.file("o.exr");
}

/// glTF with one triangle mesh used by two nodes (a shared mesh: placements), embedded buffer.
inline json shared_mesh_gltf() {
    const float pos[9] = {0, 0, 0, 1, 0, 0, 0, 0, 1};
    std::string bytes(reinterpret_cast<const char*>(pos), sizeof pos);
    std::string b64;
    static const char* tab = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    for (size_t i = 0; i < bytes.size(); i += 3) {
        uint32_t v = static_cast<uint8_t>(bytes[i]) << 16;
        if (i + 1 < bytes.size()) v |= static_cast<uint8_t>(bytes[i + 1]) << 8;
        if (i + 2 < bytes.size()) v |= static_cast<uint8_t>(bytes[i + 2]);
        b64 += tab[(v >> 18) & 63], b64 += tab[(v >> 12) & 63];
        b64 += i + 1 < bytes.size() ? tab[(v >> 6) & 63] : '=';
        b64 += i + 2 < bytes.size() ? tab[v & 63] : '=';
    }
    return {{"asset", {{"version", "2.0"}}},
            {"scene", 0},
            {"scenes", {{{"nodes", {0, 1}}}}},
            {"nodes", {{{"mesh", 0}, {"translation", {0, 0, 0}}}, {{"mesh", 0}, {"translation", {3, 0, 0}}}}},
            {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}}}}}}}}},
            {"accessors",
             {{{"bufferView", 0}, {"componentType", 5126}, {"count", 3}, {"type", "VEC3"}, {"min", {0, 0, 0}}, {"max", {1, 0, 1}}}}},
            {"bufferViews", {{{"buffer", 0}, {"byteLength", 36}}}},
            {"buffers", {{{"byteLength", 36}, {"uri", "data:application/octet-stream;base64," + b64}}}}};
}

inline std::string render_cmd(const std::string& scene, const std::string& out) {
    return "render " + scene + " -o " + out + " -q --res 16x16";
}

/// A glTF (JSON only, embedded buffer) of one triangle under a chain of `depth` nodes.
inline json gltf_chain(int depth) {
    json g = {{"asset", {{"version", "2.0"}}}, {"scene", 0}, {"scenes", {{{"nodes", {0}}}}}};
    const std::string tri = "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA";  // (0,0,0) (1,0,0) (0,1,0)
    g["buffers"] = {{{"byteLength", 36}, {"uri", "data:application/octet-stream;base64," + tri}}};
    g["bufferViews"] = {{{"buffer", 0}, {"byteLength", 36}}};
    g["accessors"] = {{{"bufferView", 0}, {"componentType", 5126}, {"count", 3}, {"type", "VEC3"}, {"min", {0, 0, 0}}, {"max", {1, 1, 0}}}};
    g["meshes"] = {{{"primitives", {{{"attributes", {{"POSITION", 0}}}}}}}};
    json nodes = json::array();
    for (int i = 0; i < depth; ++i) nodes.push_back(i + 1 < depth ? json{{"children", {i + 1}}} : json{{"mesh", 0}});
    g["nodes"] = nodes;
    return g;
}

/// A scene of the OBJ + MTL Cornell box, copied into `d` (so tests may edit its files).
inline std::string cornell_copy(const test::TempDir& d) {
    for (const auto& e : fs::directory_iterator(test::source_dir() + "/tests/data/cornell_box"))
        fs::copy_file(e.path(), d.path() / e.path().filename(), fs::copy_options::overwrite_existing);
    const json j = {{"camera", {{"position", {0, 1, 3.5}}, {"look_at", {0, 1, 0}}, {"fov", 40}}},
                    {"objects", {{{"type", "mesh"}, {"file", "CornellBox-Original.obj"}}}},
                    {"lights", {{{"type", "point"}, {"position", {0, 1.5, 0}}}}}};
    return d.write("cornell.json", j.dump());
}

inline std::string quick(const std::string& scene, const std::string& out) {
    return "render " + scene + " -o " + out + " -q --res 16x16 --spp 1 --light-samples 1";
}

inline const char* kPlyHeader =
    "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
    "element face 1\nproperty list uchar int vertex_indices\nend_header\n";

/// A scene of one PLY mesh `ply` (written as m.ply).
inline std::string ply_scene(const test::TempDir& d, const std::string& ply) {
    d.write("m.ply", ply);
    json j = test::base_scene();
    j["objects"] = {{{"type", "mesh"}, {"file", "m.ply"}}};
    d.write("s.json", j.dump());
    return d.file("s.json");
}

inline void refused(const std::string& args, std::initializer_list<std::string> parts) { test::expect_refused(args, parts); }

}  // namespace bounce::hostile
