// bounce.Scene: a scene file (or a dict of its schema) with the settings a script set on it.
// It loads as the CLI loads (load_scene with the overrides, in order), so a render through
// Python is the CLI's render of the same scene and options.
#pragma once

#include <pybind11/pybind11.h>

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "bounce/scene/json_reader.h"
#include "bounce/scene/scene.h"

namespace bounce::python {

class PyScene {
  public:
    /// From a file (.json, or a glTF/OBJ/PLY with a camera); loads it now (errors raise here).
    static PyScene from_file(const std::string& path, std::optional<double> frame);
    /// From the scene file's schema as text, named `path` (which anchors relative file names).
    static PyScene from_text(std::string text, const std::string& path, std::optional<double> frame);

    /// The scene at `frame` (default: the one it was loaded at) with its settings, then `extra`
    /// (a render's keyword arguments); the last load is kept for the same request.
    std::shared_ptr<const Scene> at(const std::vector<Override>& extra, std::optional<double> frame);
    std::shared_ptr<const Scene> current() { return at({}, frame_); }

    /// scene[key], scene[key] = value: a row of the parameter table, checked as a scene file's
    /// value is; the setting holds for every later render and frame.
    pybind11::object get(const std::string& key);
    void set(const std::string& key, pybind11::handle value);

    const std::string& path() const { return path_; }
    const std::vector<Override>& sets() const { return sets_; }
    std::optional<double> frame() const { return frame_; }

  private:
    std::string path_;
    std::optional<std::string> text_;  ///< from a dict: the document
    std::optional<double> frame_;
    std::vector<Override> sets_;
    // The last load and what it was loaded with.
    std::shared_ptr<const Scene> loaded_;
    std::vector<std::string> loaded_with_;
    std::optional<double> loaded_frame_;
};

/// The override a keyword argument of render() stands for: `name` is a row's key ("render.rays")
/// or the last part of one ("rays", "resolution").
Override keyword_override(const std::string& name, pybind11::handle value, const std::string& call);

}  // namespace bounce::python
