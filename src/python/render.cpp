#include "render.h"

#include <fmt/format.h>

#include <cmath>
#include <cstdlib>

#include "bounce/core/error.h"
#include "arguments.h"
#include "convert.h"
#include "image.h"

namespace py = pybind11;

namespace bounce::python {

RenderCall read_render_call(const std::string& name, const py::args& args, const py::kwargs& kwargs) {
    Arguments a(name, args, kwargs);
    RenderCall call;
    FrameFiles& f = call.job.files;
    f.output = a.path("output");
    f.deep_in = a.path("deep_in");
    f.deep_out = a.path("deep_out");
    f.cache_in = a.path("cache_in");
    f.cache_out = a.path("cache_out");
    f.stats_json = a.path("stats_json");
    f.base = a.path("base");
    DisplaySettings display;
    display.config = a.path("ocio_config");
    display.config_given = !display.config.empty();
    display.display = a.text("display", "");
    display.view = a.text("view", "");
    f.display = std::make_shared<const DisplayTransform>(display, std::getenv("OCIO"));
    call.job.show = a.text("show", "beauty");
    call.job.regather = a.flag("regather");
    call.job.force = a.flag("force");
    const std::string reuse = a.text("cache_reuse", "strict");
    if (reuse != "strict" && reuse != "any") a.fail("cache_reuse", py::str(reuse), "is \"strict\" or \"any\"");
    call.job.reuse_any = reuse == "any";
    call.frame = a.number("frame");
    call.progress = a.callable("progress");
    call.preview = a.callable("preview");
    py::object cancel = a.take("cancel");
    if (!cancel.is_none()) {
        if (!py::isinstance<PyCancel>(cancel))
            a.fail("cancel", cancel, fmt::format("expects a bounce.CancelToken, not a {}", type_name(cancel)));
        call.cancel = cancel.cast<std::shared_ptr<PyCancel>>();
    }
    for (const auto& [key, value] : a.rest()) call.params.push_back(keyword_override(key, value, name));
    if (!f.output.empty() && !f.output.ends_with(".exr")) a.fail("output", py::str(f.output), "the image is an OpenEXR file (.exr)");
    return call;
}

namespace {

/// Plans and runs one frame of `scene` through the driver, polled from Python (Monitor), then
/// writes its files as the CLI does; `shot` carries a sequence's state (null for a still).
py::object run_one(const std::shared_ptr<const Scene>& scene, const RenderCall& call, const FrameFiles& files, int frame, Shot* shot,
                   bool first_of_shot) {
    check_job(call.job, *scene, shot != nullptr);
    RenderRequest request = job_request(call.job, files, frame);
    if (shot && !first_of_shot) request.cache_in.clear();  // the shot carries its own cache
    Monitor monitor(call.progress, call.preview, call.cancel);
    request.cancel = &monitor.token();
    request.preview = [&monitor](const Image& image) { monitor.keep_preview(image); };
    const FrameState none;  // a still, or a frame whose shot plans it from the frame before
    const FramePlan plan = plan_frame(*scene, none, request);
    check_job_frame(call.job, files, *scene, plan);
    Stats stats;
    add_load_phases(stats, *scene);
    RenderResult r;
    monitor.run(
        [&] { r = shot ? shot->render(scene, request, stats, &monitor) : run_frame(*scene, plan, none, request, stats, &monitor); });
    // What the EXR holds: with a base, the full frame with the crop pasted over it.
    std::optional<Image> pasted = write_frame_outputs(r, files, call.job.show, stats);
    auto image = std::make_shared<Image>(pasted ? std::move(*pasted) : std::move(r.image));
    if (shot) shot->keep(r, scene);
    return wrap_image(std::move(image), py::reinterpret_steal<py::dict>(from_json(stats.to_json()).release()));
}

void warn_unread(const Scene& scene) {
    // Nothing dropped in silence: what the mesh files carry that is not read, as Python warnings.
    for (const std::string& line : scene.unread)
        if (PyErr_WarnEx(PyExc_UserWarning, line.c_str(), 1) != 0) throw py::error_already_set();
}

}  // namespace

py::object render_still(PyScene& scene, const RenderCall& call) {
    const std::optional<int> asked =
        call.frame
            ? std::optional(still_frame_number(*call.frame, call.job.files, "python", fmt::format("render(frame={:g})", *call.frame)))
            : std::nullopt;
    const std::shared_ptr<const Scene> s = scene.at(call.params, call.frame ? call.frame : scene.frame());
    const int whole = asked ? *asked : static_cast<int>(std::lround(s->frame));
    warn_unread(*s);
    return run_one(s, call, expand_frame(call.job.files, whole), whole, nullptr, true);
}

PyFrames::PyFrames(std::shared_ptr<PyScene> scene, std::vector<int> frames, RenderCall call)
    : scene_(std::move(scene)), frames_(std::move(frames)), call_(std::move(call)) {
    if (call_.frame) throw InputError("python", "render_frames(frame=...)", "give the frames as the first argument, not frame=");
    if (frames_.empty()) throw InputError("python", "render_frames()", "no frames to render");
    for (size_t i = 1; i < frames_.size(); ++i)
        if (frames_[i] != frames_[i - 1] + 1)
            throw InputError("python", fmt::format("render_frames(frames=[..., {}, {}, ...])", frames_[i - 1], frames_[i]),
                             "a shot's frames run in order, one after the other (each starts from the one before)");
    check_sequence_names(call_.job.files, "python", [](const std::string& field, const std::string& path) {
        return fmt::format("render_frames({}=\"{}\")", field, path);
    });
    const std::shared_ptr<const Scene> first = scene_->at(call_.params, frames_.front());
    check_job(call_.job, *first, true);
    if (first->shot.animated && !first->shot.contains(frames_.back()))
        throw InputError("python", fmt::format("render_frames(frames=...{})", frames_.back()), first->shot.outside(frames_.back()));
    warn_unread(*first);
}

py::object PyFrames::next() {
    if (at_ >= frames_.size()) throw py::stop_iteration();
    const int f = frames_[at_];
    const std::shared_ptr<const Scene> scene = scene_->at(call_.params, f);
    py::object image = run_one(scene, call_, expand_frame(call_.job.files, f), f, &shot_, at_ == 0);
    ++at_;
    return image;
}

}  // namespace bounce::python
