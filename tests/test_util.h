// Helpers shared by the tests: temporary folders, scenes from inline JSON, running the CLI.
#pragma once

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

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

/// A large floor quad (y = 0, normal +y) as a JSON object list.
inline nlohmann::json floor_objects(float half = 1000.0f) {
    return nlohmann::json::array({{{"type", "quad"},
                                   {"vertices", {{-half, 0, -half}, {-half, 0, half}, {half, 0, half}, {half, 0, -half}}}}});
}

/// A minimal valid scene (camera looking down at the floor) to modify in tests.
inline nlohmann::json base_scene() {
    return {{"camera", {{"position", {0, 10, 0.001}}, {"look_at", {0, 0, 0}}, {"fov", 40}, {"resolution", {16, 16}}}},
            {"objects", floor_objects()},
            {"lights", nlohmann::json::array()}};
}

inline Scene scene_from(const nlohmann::json& j, const std::vector<Override>& overrides = {}) {
    return load_scene_text(j.dump(), "inline.json", overrides);
}

}  // namespace bounce::test
