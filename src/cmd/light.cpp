#include "light.h"

#include <cstdio>
#include <cstdlib>
#include <memory>

#include "bounce/core/files.h"
#include "bounce/tool/server.h"

namespace bounce {

int run_light(const LightArgs& a) {
    check_input_file(a.scene);
    SessionOptions so;
    so.scene = a.scene, so.out_dir = a.out_dir, so.deep_in = a.deep_in, so.cache_in = a.cache_in, so.threads = a.threads, so.sets = a.sets;
    so.display = std::make_shared<const DisplayTransform>(a.display, std::getenv("OCIO"));
    ServerOptions opts;
    opts.host = a.bind, opts.port = a.port, opts.web_dir = BOUNCE_WEB_DIR, opts.three_dir = BOUNCE_THREE_DIR;
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
