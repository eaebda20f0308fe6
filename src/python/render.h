// Scene.render (a still) and Scene.render_frames (a shot): the CLI's `render` and `render
// --frames`, step for step (frontend/frame_job.h): the same refusals, the same request, the same
// files written in the same order, so the images are the CLI's bit for bit.
#pragma once

#include <pybind11/pybind11.h>

#include <memory>
#include <vector>

#include "bounce/render/shot.h"
#include "frontend/frame_job.h"
#include "runner.h"
#include "scene.h"

namespace bounce::python {

/// What a render call asks beyond the scene (its keyword arguments, read).
struct RenderCall {
    FrameJob job;
    std::vector<Override> params;  ///< keyword arguments naming parameters (rays=256)
    std::optional<double> frame;
    pybind11::object progress, preview;
    std::shared_ptr<PyCancel> cancel;
};
RenderCall read_render_call(const std::string& call, const pybind11::args& args, const pybind11::kwargs& kwargs);

/// A still of `scene`, as `bounce render` renders it.
pybind11::object render_still(PyScene& scene, const RenderCall& call);

/// The frames of a shot in order, each starting from what the one before left (records kept as
/// `bounce render --frames` keeps them): an iterator that renders a frame per step.
class PyFrames {
  public:
    PyFrames(std::shared_ptr<PyScene> scene, std::vector<int> frames, RenderCall call);
    /// The next frame's image; throws pybind11::stop_iteration after the last.
    pybind11::object next();

  private:
    std::shared_ptr<PyScene> scene_;
    std::vector<int> frames_;
    size_t at_ = 0;
    RenderCall call_;
    Shot shot_;
};

}  // namespace bounce::python
