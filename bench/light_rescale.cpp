// Issue 28 item 7: a light's intensity or colour edit in the lighting tool, on records that keep
// their bounce light per light (render.light_parts, the tool's default). Drives the tool's engine
// (LightingSession, as the web page does) on SCENE at RES with 2 threads: a new deep file and
// gather; then per light, an intensity edit (x1.5) and a colour edit, each re-shaded (timed,
// median of 3) and compared with a full re-gather at the new values (relative RMSE of the
// indirect and beauty layers). Also the memory of the records with and without parts.
// Prints a Markdown table (docs/lighting-tool.md quotes it).
//
//   bounce_light_rescale SCENE [WxH]
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "bounce/core/image_compare.h"
#include "bounce/tool/session.h"

namespace bounce {
namespace {

using nlohmann::json;

double seconds(SessionAction action, LightingSession& s) {
    const auto t0 = std::chrono::steady_clock::now();
    s.start(action);
    s.wait();
    const json st = s.status();
    if (st["state"] != "done") throw std::runtime_error("render failed: " + st["message"].get<std::string>());
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// The scene's lights (the largest N of the "lights.N.*" rows, plus 1).
size_t edits_lights(const LightingSession& s) {
    size_t n = 0;
    for (const json& r : s.params()) {
        const std::string key = r["key"];
        if (key.starts_with("lights.")) n = std::max<size_t>(n, std::stoul(key.substr(7)) + 1);
    }
    return n;
}

double layer_error(const Image& a, const Image& b, const std::string& layer) {
    return compare_images(a, b, layer, "re-shade", "re-gather").at(0).rel_rmse;
}

SessionOptions options(const std::string& scene, const std::string& res, const std::string& out, bool parts) {
    SessionOptions o;
    o.scene = scene;
    o.out_dir = out;
    o.threads = 2;
    o.sets = {"camera.resolution=[" + res.substr(0, res.find('x')) + "," + res.substr(res.find('x') + 1) + "]", "render.preview=false"};
    o.default_to_light_parts = parts;
    return o;
}

int run(const std::string& scene, const std::string& res) {
    const auto tmp = std::filesystem::temp_directory_path() / "bounce-light-rescale";
    std::filesystem::remove_all(tmp);
    LightingSession s(options(scene, res, (tmp / "parts").string(), true));
    const double first = seconds(SessionAction::Rasterize, s);
    const json st0 = s.status()["stats"];
    fmt::print("new deep file + gather (light parts): {:.2f} s, {} records, {} lights: {} bytes of parts per record\n", first,
               st0.value("records", 0.0), edits_lights(s), 160 + 120 * edits_lights(s));
    fmt::print(
        "| edit | re-shade (median of 3) | bounce light stale | new records | rel. RMSE indirect vs re-gather | beauty | phases (s) |\n");
    fmt::print("|---|---|---|---|---|---|---|\n");
    const json rows = s.params();
    std::vector<std::pair<std::string, json>> edits;
    for (const json& r : rows) {
        const std::string key = r["key"];
        if (!key.starts_with("lights.")) continue;
        if (key.ends_with(".intensity")) edits.emplace_back(key, r["value"].get<double>() * 1.5);
        if (key.ends_with(".color")) edits.emplace_back(key, json{1.0, 0.6, 0.3});
    }
    for (const auto& [key, value] : edits) {
        s.edit(key, value);
        std::vector<double> t;
        for (int i = 0; i < 3; ++i) t.push_back(seconds(SessionAction::Reshade, s));
        std::sort(t.begin(), t.end());
        const json st = s.status();
        const Image reshaded = s.image();
        const double records_new = st["stats"].value("records_new", 0.0);
        const bool stale = st.value("bounce_stale", false);
        seconds(SessionAction::Regather, s);
        const Image regathered = s.image();
        fmt::print("| {} = {} | {:.3f} s | {} | {} | {:.2e} | {:.2e} | {} |\n", key, value.dump(), t[1], stale ? "yes" : "no", records_new,
                   layer_error(reshaded, regathered, "indirect"), layer_error(reshaded, regathered, "beauty"),
                   st["stats"]["phases_s"].dump());
    }
    // Memory: the same frame without parts.
    LightingSession plain(options(scene, res, (tmp / "plain").string(), false));
    const double plain_first = seconds(SessionAction::Rasterize, plain);
    const json sp = plain.status()["stats"];
    fmt::print("new deep file + gather (no parts): {:.2f} s, {} records\n", plain_first, sp.value("records", 0.0));
    plain.edit(edits.front().first, edits.front().second);
    std::vector<double> t;
    for (int i = 0; i < 3; ++i) t.push_back(seconds(SessionAction::Reshade, plain));
    std::sort(t.begin(), t.end());
    fmt::print("no parts, {} edit re-shaded (stale): median {:.3f} s, phases {}\n", edits.front().first, t[1],
               plain.status()["stats"]["phases_s"].dump());
    std::filesystem::remove_all(tmp);
    return 0;
}

}  // namespace
}  // namespace bounce

int main(int argc, char** argv) {
    if (argc < 2) {
        std::fprintf(stderr, "usage: bounce_light_rescale SCENE [WxH]\n");
        return 2;
    }
    try {
        return bounce::run(argv[1], argc > 2 ? argv[2] : "640x360");
    } catch (const std::exception& e) {
        std::fprintf(stderr, "bounce_light_rescale: %s\n", e.what());
        return 1;
    }
}
