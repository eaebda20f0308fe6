#include "session.h"

#include <pybind11/stl.h>

#include <fmt/format.h>

#include <memory>

#include "arguments.h"
#include "bounce/core/error.h"
#include "bounce/tool/session.h"
#include "convert.h"
#include "errors.h"
#include "frontend/environment.h"
#include "image.h"
#include "runner.h"

namespace py = pybind11;

namespace bounce::python {

namespace {

struct PySession {
    std::unique_ptr<LightingSession> session;
};

std::shared_ptr<PySession> open_session(const py::args& args, const py::kwargs& kwargs) {
    Arguments a("Session", args, kwargs);
    SessionOptions so;
    so.scene = a.path("scene");
    so.out_dir = a.path("out_dir");
    if (so.scene.empty() || so.out_dir.empty()) throw InputError("python", "Session()", "give scene= and out_dir=");
    so.deep_in = a.path("deep_in");
    so.cache_in = a.path("cache_in");
    py::object threads = a.take("threads");
    if (!threads.is_none()) {
        const nlohmann::json t = to_json(threads, "python", "Session(threads=...)");
        if (!t.is_number_integer() || t.get<int64_t>() < 0 || t.get<int64_t>() > 4096)
            a.fail("threads", threads, "expects an integer in [0, 4096] (0: all cores)");
        so.threads = t.get<int>();
    }
    if (const auto rest = a.rest(); !rest.empty()) a.fail(rest.front().first, rest.front().second, "is not an argument of Session");
    check_input_file(so.scene);
    so.resources = load_resources_from_environment();
    auto out = std::make_shared<PySession>();
    out->session = std::make_unique<LightingSession>(so);
    return out;
}

/// Renders `action` (default: what the edits need) and returns the session's image.
py::object render(PySession& self, const py::args& args, const py::kwargs& kwargs) {
    Arguments a("Session.render", args, kwargs);
    LightingSession& s = *self.session;
    const std::string name = a.text("action", "");
    const SessionAction action = name.empty() ? s.pending() : parse_session_action(name);
    py::object progress = a.callable("progress");
    if (const auto rest = a.rest(); !rest.empty()) a.fail(rest.front().first, rest.front().second, "is not an argument of Session.render");
    Monitor monitor(progress, py::none(), nullptr);
    monitor.run([&] { s.start(action), s.wait(); },
                [&] {
                    if (monitor.token().cancelled()) return s.stop();
                    const nlohmann::json p = s.status().value("progress", nlohmann::json::object());
                    if (p.contains("phase") && p["phase"].is_string() && !p["phase"].get<std::string>().empty())
                        monitor.update(p["phase"], p.value("done", uint64_t{0}), p.value("total", uint64_t{0}), 0);
                });
    const nlohmann::json status = s.status();
    const std::string state = status.value("state", "");
    if (state == "failed") raise_error(status.value("message", "the session's render failed"));
    if (state == "cancelled") throw Cancelled();
    return wrap_image(std::make_shared<Image>(s.image()),
                      py::reinterpret_steal<py::dict>(from_json(status.value("stats", nlohmann::json::object())).release()));
}

}  // namespace

void add_session(py::module_& m) {
    py::class_<PySession, std::shared_ptr<PySession>>(
        m, "Session",
        "The lighting tool's engine: a scene whose deep buffer and cache stay between renders "
        "(docs/python.md). Session(scene=, out_dir=, deep_in=, cache_in=, threads=0).")
        .def(py::init(&open_session))
        .def("__setitem__",
             [](PySession& self, const std::string& key, py::handle value) {
                 self.session->edit(key, to_json(value, "python", fmt::format("session[\"{}\"]", key)));
             })
        .def(
            "edit",
            [](PySession& self, const std::string& key, py::handle value) {
                return from_json(self.session->edit(key, to_json(value, "python", fmt::format("session[\"{}\"]", key))));
            },
            py::arg("key"), py::arg("value"), "Sets a value as the tool's spreadsheet does; returns {key, value, needs}.")
        .def_property_readonly(
            "pending",
            [](PySession& self) -> py::object {
                const nlohmann::json p = self.session->status().value("pending", nlohmann::json());
                return from_json(p);
            },
            "The least action that shows every edit since the last render (reshade, regather, rasterize), or None.")
        .def("render", &render,
             "render(action=None, progress=None) -> bounce.Image: the pending action (or the one named), the deep buffer and "
             "cache kept for the next; Ctrl-C or a raising callback stops it.")
        .def("params", [](PySession& self) { return from_json(self.session->params()); })
        .def("status", [](PySession& self) { return from_json(self.session->status()); })
        .def(
            "save_scene", [](PySession& self, const std::string& name) { return self.session->save_scene(name); }, py::arg("name"));
}

}  // namespace bounce::python
