// The `bounce` Python module's compiled part (bounce._bounce): thin over the library, with no
// logic of its own; python/bounce/ re-exports it (docs/python.md).
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <filesystem>

#include "bounce/config/params.h"
#include "bounce/core/error.h"
#include "bounce/core/version.h"
#include "convert.h"
#include "errors.h"
#include "image.h"
#include "render.h"
#include "runner.h"
#include "scene.h"
#include "session.h"
#include "tools.h"

namespace py = pybind11;
using namespace bounce;
using namespace bounce::python;

namespace {

std::optional<double> frame_arg(py::handle f, const char* call) {
    if (f.is_none()) return std::nullopt;
    if (PyBool_Check(f.ptr()) || !(PyFloat_Check(f.ptr()) || PyIndex_Check(f.ptr()))) throw InputError("python", call, "frame is a number");
    const double d = py::float_(py::reinterpret_borrow<py::object>(f)).cast<double>();
    if (!is_frame_number(d)) throw InputError("python", call, fmt::format("a frame must be a finite number within +-{:g}", kMaxFrame));
    return d;
}

std::vector<int> frames_arg(py::handle frames) {
    std::vector<int> out;
    if (!py::isinstance<py::iterable>(frames) || py::isinstance<py::str>(frames))
        throw InputError("python", "render_frames(frames=...)",
                         "expects frame numbers (a range or a list of ints), not a " + type_name(frames));
    for (py::handle f : py::reinterpret_borrow<py::iterable>(frames)) {
        if (PyBool_Check(f.ptr()) || !PyIndex_Check(f.ptr()))
            throw InputError("python", "render_frames(frames=...)", "its frames are ints, not " + type_name(f));
        const long long v = py::int_(py::reinterpret_borrow<py::object>(f)).cast<long long>();
        if (!is_frame_number(static_cast<double>(v)))
            throw InputError("python", fmt::format("render_frames(frames=[... {} ...])", v),
                             fmt::format("a frame must be within +-{:g}", kMaxFrame));
        out.push_back(static_cast<int>(v));
    }
    return out;
}

void add_scene_class(py::module_& m) {
    py::class_<PyScene, std::shared_ptr<PyScene>>(m, "Scene", "A scene file with the settings a script gives it (docs/python.md).")
        .def_static(
            "load",
            [](py::handle path, py::handle frame) {
                return std::make_shared<PyScene>(
                    PyScene::from_file(fspath(path, "Scene.load()"), frame_arg(frame, "Scene.load(frame=...)")));
            },
            py::arg("path"), py::arg("frame") = py::none(), "Loads a scene file (.json, or a glTF/OBJ/PLY with a camera) at `frame`.")
        .def_static(
            "from_dict",
            [](py::handle d, py::handle path, py::handle frame) {
                if (!py::isinstance<py::dict>(d))
                    throw InputError("python", "Scene.from_dict()", "expects a dict of the scene file's schema, not a " + type_name(d));
                const std::string name =
                    path.is_none() ? (std::filesystem::current_path() / "<dict>").string() : fspath(path, "Scene.from_dict(path=...)");
                return std::make_shared<PyScene>(
                    PyScene::from_text(to_json(d, name).dump(), name, frame_arg(frame, "Scene.from_dict(frame=...)")));
            },
            py::arg("scene"), py::arg("path") = py::none(), py::arg("frame") = py::none(),
            "A scene from a dict of the scene file's schema; `path` (default: <dict> in the working folder) names it in errors and anchors "
            "its relative file names.")
        .def("__getitem__", &PyScene::get, py::arg("key"),
             "A parameter (\"render.rays\") or any value of the scene (\"lights.0.intensity\").")
        .def("__setitem__", &PyScene::set, py::arg("key"), py::arg("value"),
             "Sets it for every later render, checked as the scene file's value is.")
        .def(
            "params", [](PyScene& s) { return from_json(param_values(*s.current(), ~0u)); }, "Every parameter's value, by key.")
        .def(
            "description", [](PyScene& s) { return from_json(s.current()->description); },
            "The scene as loaded: the file's JSON with the settings applied.")
        .def_property_readonly("path", &PyScene::path)
        .def_property_readonly(
            "frame", [](PyScene& s) { return s.current()->frame; }, "The frame it is loaded at.")
        .def_property_readonly(
            "shot",
            [](PyScene& s) {
                const ShotSettings& shot = s.current()->shot;
                return py::make_tuple(shot.first, shot.last);
            },
            "(first, last) frames of the shot.")
        .def_property_readonly(
            "settings",
            [](const PyScene& s) {
                std::vector<std::string> out;
                for (const Override& o : s.sets()) out.push_back(o.assignment);
                return out;
            },
            "The settings given to it, as --set assignments.")
        .def_property_readonly(
            "unread", [](PyScene& s) { return s.current()->unread; }, "What its mesh files carry that bounce does not read.")
        .def(
            "render",
            [](PyScene& s, const py::args& args, const py::kwargs& kwargs) {
                return render_still(s, read_render_call("render", args, kwargs));
            },
            "render(output=None, deep_in=, deep_out=, cache_in=, cache_out=, stats_json=, base=, show='beauty', regather=False, "
            "force=False, "
            "cache_reuse='strict', frame=None, progress=None, preview=None, cancel=None, ocio_config=, display=, view=, **params) -> "
            "bounce.Image. "
            "**params are parameters by name (gi='cache', rays=256, resolution=[640, 360]).")
        .def(
            "render_frames",
            [](std::shared_ptr<PyScene> s, py::handle frames, const py::kwargs& kwargs) {
                return std::make_shared<PyFrames>(std::move(s), frames_arg(frames), read_render_call("render_frames", py::args(), kwargs));
            },
            py::arg("frames"),
            "render_frames(frames, **render's arguments): an iterator of bounce.Images, one per frame; file names need ####.")
        .def("__repr__", [](PyScene& s) { return fmt::format("<bounce.Scene {}>", s.path()); });
    py::class_<PyFrames, std::shared_ptr<PyFrames>>(m, "Frames", "A shot being rendered: iterate for each frame's bounce.Image.")
        .def("__iter__", [](std::shared_ptr<PyFrames> f) { return f; })
        .def("__next__", &PyFrames::next);
}

}  // namespace

PYBIND11_MODULE(_bounce, m) {
    m.doc() = "bounce: one bounce of diffuse interreflection and ambient occlusion through an irradiance cache.";
    m.attr("__version__") = std::string(bounce_version());
    add_errors(m);
    py::class_<PyCancel, std::shared_ptr<PyCancel>>(m, "CancelToken",
                                                    "Hand to render(cancel=...); .cancel() from any thread stops it within a tile.")
        .def(py::init<>())
        .def("cancel", [](PyCancel& c) { c.token.cancel(); })
        .def_property_readonly("cancelled", [](const PyCancel& c) { return c.token.cancelled(); });
    add_image(m);
    add_scene_class(m);
    add_tools(m);
    add_session(m);
}
