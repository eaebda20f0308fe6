// `bounce light`: the lighting tool's command (docs/lighting-tool.md).
#pragma once

#include <string>
#include <vector>

#include "bounce/core/display.h"

namespace bounce {

struct LightArgs {
    std::string scene, out_dir = "out/light", deep_in, cache_in, bind = "127.0.0.1";
    int port = 8080, threads = 0;
    std::vector<std::string> sets;
    DisplaySettings display;  ///< the view's OpenColorIO config, display and view
};

/// Starts the session and the server; prints the URL; serves until interrupted.
int run_light(const LightArgs& a);

}  // namespace bounce
