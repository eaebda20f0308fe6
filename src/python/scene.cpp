#include "scene.h"

#include <pybind11/stl.h>

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <filesystem>

#include "bounce/config/params.h"
#include "bounce/core/error.h"
#include "bounce/scene/scene_load.h"
#include "convert.h"
#include "frontend/environment.h"

namespace py = pybind11;

namespace bounce::python {

namespace {

std::string repr_of(py::handle v) { return py::repr(v).cast<std::string>(); }

/// The JSON pointer of a dotted key ("lights.0.intensity" -> "/lights/0/intensity").
std::string pointer_of(const std::string& key) {
    std::string p = "/" + key;
    std::replace(p.begin(), p.end(), '.', '/');
    return p;
}

LoadOptions options_at(std::optional<double> frame) {
    LoadOptions options = load_options_from_environment();
    options.frame = frame;
    if (frame) options.frame_origin = fmt::format("frame={:g}", *frame);
    return options;
}

}  // namespace

PyScene PyScene::from_file(const std::string& path, std::optional<double> frame) {
    PyScene s;
    s.path_ = path;
    s.frame_ = frame;
    s.current();
    return s;
}

PyScene PyScene::from_text(std::string text, const std::string& path, std::optional<double> frame) {
    PyScene s;
    s.path_ = path;
    s.text_ = std::move(text);
    s.frame_ = frame;
    s.current();
    return s;
}

std::shared_ptr<const Scene> PyScene::at(const std::vector<Override>& extra, std::optional<double> frame) {
    std::vector<Override> all = sets_;
    all.insert(all.end(), extra.begin(), extra.end());
    std::vector<std::string> with;
    for (const Override& o : all) with.push_back(o.assignment);
    if (loaded_ && with == loaded_with_ && frame == loaded_frame_) return loaded_;
    const auto start = std::chrono::steady_clock::now();
    Scene scene = text_ ? load_scene_text(*text_, path_, all, options_at(frame)) : load_scene(path_, all, options_at(frame));
    if (text_) scene.load_times.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    loaded_ = std::make_shared<const Scene>(std::move(scene));
    loaded_with_ = std::move(with);
    loaded_frame_ = frame;
    return loaded_;
}

py::object PyScene::get(const std::string& key) {
    const std::shared_ptr<const Scene> s = current();
    if (find_param(scene_params(), key)) return from_json(param_value(*s, key));
    // Any other value of the scene file, as the loaded scene describes it.
    const nlohmann::json::json_pointer at(pointer_of(key));
    if (key.empty() || !s->description.contains(at)) throw py::key_error(fmt::format("the scene has no value \"{}\"", key));
    return from_json(s->description.at(at));
}

void PyScene::set(const std::string& key, py::handle value) {
    const std::string origin = fmt::format("scene[\"{}\"] = {}", key, repr_of(value));
    const nlohmann::json v = to_json(value, "python", origin);
    Override o(key + "=" + v.dump(), origin, "python");
    if (const Param* p = find_param(scene_params(), key)) {
        // A parameter is checked by the table now (its check is of the value alone: scratch
        // settings serve, and no load is made); the scene loads with it when next needed.
        Camera camera;
        RenderSettings render;
        try {
            set_param_value(ParamsOut{camera, render}, key, v);
        } catch (const std::invalid_argument& e) {
            throw InputError("python", origin + " (" + pointer_of(p->key) + ")", e.what());
        }
        std::erase_if(sets_, [&](const Override& was) { return was.assignment.starts_with(key + "="); });
        sets_.push_back(std::move(o));
        return;
    }
    // Any other value (a light's intensity, a material's colour): the scene loads with it now,
    // so a bad value is refused here, and the scene stays as it was.
    sets_.push_back(std::move(o));
    try {
        current();
    } catch (...) {
        sets_.pop_back();
        throw;
    }
}

Override keyword_override(const std::string& name, py::handle value, const std::string& call) {
    const Param* p = find_param(scene_params(), name);
    for (const char* section : {"render.", "camera."})
        if (!p) p = find_param(scene_params(), section + name);
    const std::string origin = fmt::format("{}({}={})", call, name, repr_of(value));
    if (!p) {
        std::vector<std::string> names;
        for (const Param& row : scene_params()) names.push_back(row.name());
        const std::string hint = closest_match(name, names);
        throw InputError("python", origin,
                         fmt::format("no parameter \"{}\"{} (bounce.params() lists them)", name,
                                     hint.empty() ? "" : ", did you mean \"" + hint + "\"?"));
    }
    return Override(p->key + "=" + to_json(value, "python", origin).dump(), origin, "python");
}

}  // namespace bounce::python
