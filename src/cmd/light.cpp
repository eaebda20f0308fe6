#include "light.h"

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <tuple>
#include <utility>
#include <memory>

#include "frontend/environment.h"
#include "bounce/core/files.h"
#include "bounce/tool/server.h"

namespace bounce {

namespace {

/// The page's folder and three.js's: beside an installed binary (PREFIX/bin/bounce finds
/// PREFIX/share/bounce/web and .../three), else the source tree's it was built from.
std::pair<std::string, std::string> page_folders() {
    std::error_code ec;
    const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
    const std::filesystem::path share = exe.parent_path().parent_path() / "share" / "bounce";
    if (!ec && std::filesystem::is_regular_file(share / "web" / "index.html", ec))
        return {(share / "web").string(), (share / "three").string()};
    return {BOUNCE_WEB_DIR, BOUNCE_THREE_DIR};
}

}  // namespace

int run_light(const LightArgs& a) {
    check_input_file(a.scene);
    SessionOptions so;
    so.scene = a.scene, so.out_dir = a.out_dir, so.deep_in = a.deep_in, so.cache_in = a.cache_in, so.threads = a.threads, so.sets = a.sets;
    so.display = std::make_shared<const DisplayTransform>(a.display, std::getenv("OCIO"));
    so.resources = load_resources_from_environment();
    ServerOptions opts;
    opts.host = a.bind, opts.port = a.port;
    std::tie(opts.web_dir, opts.three_dir) = page_folders();
    LightingSession session(so);  // refuses a bad scene, deep or cache file before serving
    LightingServer server(session, opts);
    server.bind();
    // The token in the URL is the page's key: only a page opened from it may drive the tool.
    std::printf("bounce light: %s  (scene %s, files in %s; Ctrl-C stops)\n", server.url().c_str(), a.scene.c_str(), a.out_dir.c_str());
    std::fflush(stdout);
    server.listen();
    return 0;
}

}  // namespace bounce
