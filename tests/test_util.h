// Helpers shared by the tests: temporary folders, scenes from inline JSON, running the CLI.
#pragma once

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <functional>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "frontend/environment.h"
#include "bounce/core/error.h"
#include "bounce/core/image.h"
#include "bounce/render/frame_plan.h"
#include "bounce/scene/scene_load.h"

namespace bounce::test {

/// A fresh directory under the build's temp area, removed at destruction.
class TempDir {
  public:
    TempDir() {
        auto base = std::filesystem::temp_directory_path() / "bounce-tests";
        std::filesystem::create_directories(base);
        std::string tmpl = (base / "XXXXXX").string();
        path_ = mkdtemp(tmpl.data());
    }
    ~TempDir() {
        std::error_code ec;
        std::filesystem::remove_all(path_, ec);
    }
    std::string file(const std::string& name) const { return (path_ / name).string(); }
    std::string write(const std::string& name, const std::string& text) const {
        std::ofstream(file(name), std::ios::binary) << text;
        return file(name);
    }
    const std::filesystem::path& path() const { return path_; }

  private:
    std::filesystem::path path_;
};

inline std::string source_dir() { return BOUNCE_SOURCE_DIR; }

/// The plan of a still of `s`: the settings it resolves for each stage (tests that call a
/// stage directly take them from here, as a frame's passes do).
inline FramePlan still_plan(const Scene& s) { return plan_frame(s, FrameState{}, RenderRequest{}); }
inline std::string cornell_scene() { return source_dir() + "/scenes/cornell/cornell.json"; }

/// Runs the bounce binary with `args`; returns the exit status, stderr in `err`.
inline int run_bounce(const std::string& args, std::string* err = nullptr) {
    TempDir d;
    std::string cmd = std::string(BOUNCE_BINARY) + " " + args + " 2>" + d.file("err.txt") + " >/dev/null";
    int rc = std::system(cmd.c_str());
    if (err) {
        std::ifstream in(d.file("err.txt"));
        err->assign(std::istreambuf_iterator<char>(in), {});
    }
    return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

/// Runs `command` in sh (e.g. with a ulimit before bounce); the exit status, stderr in `err`.
inline int run_bounce_shell(const std::string& command, std::string* err = nullptr) {
    TempDir d;
    std::string cmd = "sh -c '" + command + "' 2>" + d.file("err.txt") + " >/dev/null";
    int rc = std::system(cmd.c_str());
    if (err) {
        std::ifstream in(d.file("err.txt"));
        err->assign(std::istreambuf_iterator<char>(in), {});
    }
    return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

/// Runs bounce with `args`, expects exit 2 and every one of `parts` in its one-line message.
inline void expect_refused(const std::string& args, const std::vector<std::string>& parts) {
    std::string err;
    EXPECT_EQ(run_bounce(args, &err), 2) << args << " -> " << err;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
    for (const auto& p : parts) EXPECT_NE(err.find(p), std::string::npos) << args << " -> " << err << " lacks " << p;
}

/// A cache file's bytes with its JSON header edited by `edit` and its checksum made valid again
/// (FNV-1a, as cache_file.cpp writes it): what a crafted file would hold.
inline std::string with_cache_header(const std::string& bytes, const std::function<void(nlohmann::json&)>& edit) {
    uint32_t length = 0;
    std::memcpy(&length, bytes.data() + 12, 4);
    nlohmann::json header = nlohmann::json::parse(bytes.substr(16, length));
    edit(header);
    const std::string text = header.dump();
    uint64_t sum = 0xcbf29ce484222325ULL;
    for (char c : text) sum = (sum ^ static_cast<uint8_t>(c)) * 0x100000001b3ULL;
    const auto n = static_cast<uint32_t>(text.size());
    std::string out = bytes.substr(0, 12);
    out.append(reinterpret_cast<const char*>(&n), 4).append(text).append(reinterpret_cast<const char*>(&sum), 8);
    return out + bytes.substr(16 + length + 8);
}

/// The bytes of a file ("" if it cannot be read).
inline std::string bytes_of(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), {}};
}

/// Writes a w x h image whose every pixel is `pixel` (one value per channel; float EXR, else 8-bit).
inline void write_constant_image(const std::string& path, int w, int h, const std::vector<float>& pixel) {
    auto out = OIIO::ImageOutput::create(path);
    ASSERT_TRUE(out);
    const int channels = static_cast<int>(pixel.size());
    OIIO::ImageSpec spec(w, h, channels, path.ends_with(".exr") ? OIIO::TypeDesc::FLOAT : OIIO::TypeDesc::UINT8);
    std::vector<float> px;
    px.reserve(static_cast<size_t>(w) * h * channels);
    for (int i = 0; i < w * h; ++i) px.insert(px.end(), pixel.begin(), pixel.end());
    ASSERT_TRUE(out->open(path, spec) && out->write_image(OIIO::TypeDesc::FLOAT, px.data()) && out->close());
}

/// Writes a w x h image of `channels` channels, every value `v` (float EXR, else 8-bit).
inline void write_constant_image(const std::string& path, int w, int h, int channels, float v) {
    write_constant_image(path, w, h, std::vector<float>(static_cast<size_t>(channels), v));
}

/// A large floor quad (y = 0, normal +y) as a JSON object list.
inline nlohmann::json floor_objects(float half = 1000.0f) {
    return nlohmann::json::array(
        {{{"type", "quad"}, {"vertices", {{-half, 0, -half}, {-half, 0, half}, {half, 0, half}, {half, 0, -half}}}}});
}

/// A minimal valid scene (camera looking down at the floor) to modify in tests.
inline nlohmann::json base_scene() {
    return {{"camera", {{"position", {0, 10, 0.001}}, {"look_at", {0, 0, 0}}, {"fov", 40}, {"resolution", {16, 16}}}},
            {"objects", floor_objects()},
            {"lights", nlohmann::json::array()}};
}

/// A scene from inline JSON, loaded as the command line loads one (its folders from the
/// environment: the tests that set BOUNCE_MESH_CACHE or BOUNCE_IMAGE_CACHE drive it so).
inline Scene scene_from(const nlohmann::json& j, const std::vector<Override>& overrides = {}) {
    return load_scene_text(j.dump(), "inline.json", overrides, load_options_from_environment());
}

/// Runs `f`, expects an InputError whose message contains every string of `parts`.
template <typename F>
void expect_input_error(F f, const std::vector<std::string>& parts) {
    try {
        f();
        ADD_FAILURE() << "no error raised";
    } catch (const InputError& e) {
        std::string msg = e.what();
        for (const auto& p : parts) EXPECT_NE(msg.find(p), std::string::npos) << "missing \"" << p << "\" in: " << msg;
        EXPECT_EQ(msg.find('\n'), std::string::npos) << "not one line: " << msg;
    }
}

/// Every channel of every layer of `a` equals `b`'s, bit for bit; returns how many differ.
inline size_t differing_values(const Image& a, const Image& b) {
    size_t n = 0;
    EXPECT_EQ(a.layers.size(), b.layers.size());
    for (const Layer& la : a.layers) {
        const Layer* lb = b.find(la.name);
        if (!lb || lb->data.size() != la.data.size()) {
            ADD_FAILURE() << "layer " << la.name << " differs in shape";
            ++n;
            continue;
        }
        size_t here = 0;
        for (size_t i = 0; i < la.data.size(); ++i) here += std::memcmp(&la.data[i], &lb->data[i], sizeof(float)) != 0;
        if (here) std::printf("layer %s: %zu values differ\n", la.name.c_str(), here);
        n += here;
    }
    return n;
}

}  // namespace bounce::test
