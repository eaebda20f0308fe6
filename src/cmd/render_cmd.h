// `bounce render`: one frame or a sequence of frames from a scene file (docs/scene-format.md).
#pragma once

#include <CLI/CLI.hpp>
#include <memory>
#include <optional>
#include <cstdint>
#include <string>
#include <vector>

#include "bounce/core/communicator.h"
#include "bounce/core/progress.h"
#include "bounce/render/frame.h"
#include "frontend/frame_job.h"
#include "bounce/scene/json_reader.h"

namespace bounce {

/// How an MPI job shares a --frames range among its ranks.
enum class Distribute : uint8_t {
    Tiles,   ///< every frame on every rank, a share of its tiles each
    Frames,  ///< a chunk of frames per rank
};
/// "tiles" or "frames" (--distribute); InputError naming the flag otherwise.
Distribute parse_distribute(const std::string& name);

struct RenderArgs {
    FrameJob job;  ///< the files and how the cache is treated
    std::vector<std::string> sets;
    std::vector<Override> flags;  ///< from the parameter table's flags
    std::string frames;
    std::optional<double> frame;  ///< default: the shot's first frame
    bool stats = false, quiet = false, resume = false;
    /// Under mpirun: the job's ranks (null: this process alone), and how a --frames range is
    /// shared among them: "tiles" (every frame on every rank) or "frames" (a chunk per rank).
    Communicator* comm = nullptr;
    std::string distribute = "tiles";
    DisplaySettings display;  ///< the PNG's OpenColorIO config, display and view
};

/// Adds the render command's options to `render`.
void add_render_options(CLI::App& render, RenderArgs& a);
/// Renders the frame or the frames the arguments ask for.
int run_render(const RenderArgs& a);

/// --ocio-config, --display, --view (render and light).
void add_display_options(CLI::App& command, DisplaySettings& display);

/// Progress on stderr: a bar on a terminal, log lines otherwise, nothing with -q.
std::unique_ptr<ProgressSink> make_progress(bool quiet);

}  // namespace bounce
