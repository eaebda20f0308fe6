// The visibility pass: the frame's deep buffer traced, read from a deep file or taken over
// from the previous frame, and the window the other passes work in.
#include "bounce/render/frame_passes.h"

#include <fmt/format.h>

#include "bounce/core/error.h"
#include "bounce/render/distributed.h"
#include "bounce/render/render.h"

namespace bounce {

namespace {

/// The window of `deep` the plan gathers in, checked against what the deep buffer covers.
DeepBuffer window_of(const DeepBuffer& deep, const FramePlan& plan, const std::string& origin, bool cropped) {
    // Without a crop, a deep file of a window renders that window.
    if (!cropped) return deep;
    const auto& c = plan.window;
    if (c[0] < deep.x0 || c[2] < deep.y0 || c[1] > deep.x0 + deep.width || c[3] > deep.y0 + deep.height)
        throw InputError(origin, "",
                         fmt::format("the deep file covers pixels [{}, {}) x [{}, {}), not the crop", deep.x0, deep.x0 + deep.width,
                                     deep.y0, deep.y0 + deep.height));
    const auto& g = plan.gather_window;
    return sub_window(deep, {std::max(deep.x0, g[0]), std::min(deep.x0 + deep.width, g[1]), std::max(deep.y0, g[2]),
                             std::min(deep.y0 + deep.height, g[3])});
}

}  // namespace

VisibilityResult visibility_pass(const FrameContext& ctx, const VisibilityStep& step, const FramePlan& plan, const FrameState& previous) {
    const Scene& scene = ctx.scene;
    const bool cropped = step.crop;
    VisibilityResult out;
    switch (step.source) {
        case DeepSource::Previous:
            validate_deep_for_scene(*previous.deep, scene, "the session's deep buffer");
            out.gathered = window_of(*previous.deep, plan, "the session's deep buffer", cropped);
            break;
        case DeepSource::ReadFile: {
            DeepBuffer deep;
            {
                PhaseTimer t(ctx.stats, "read deep");
                deep = read_deep(step.deep_in);
            }
            validate_deep_for_scene(deep, scene, step.deep_in);
            out.gathered = window_of(deep, plan, step.deep_in, cropped);
            break;
        }
        case DeepSource::Trace: {
            check_camera_sees_geometry(scene, ctx.accel);
            PhaseTimer t(ctx.stats, "visibility");
            if (ctx.comm.size() == 1) {
                out.gathered = render_visibility(scene, ctx.accel, step.settings, ctx.stats, ctx.progress, plan.gather_window);
                break;
            }
            // Each process keeps the fragments of its own tiles, unless a crop's tiles differ
            // from the gathered window's or rank 0 writes the deep file.
            out.gathered = visibility_in_tiles(ctx.comm, scene, ctx.accel, step.settings, plan.tiling().tile_size, ctx.stats,
                                               plan.gather_window, step.every_tile);
            break;
        }
    }
    if (cropped) out.crop = sub_window(out.gathered, plan.window);
    return out;
}

}  // namespace bounce
