// Python values and the scene file's JSON, both ways: what `Scene.from_dict`, `scene[key] = v`
// and the keyword arguments of `render` hand to the library, checked on the way in so that a
// value JSON cannot hold (NaN, an object of another type) is refused with its place named.
#pragma once

#include <pybind11/pybind11.h>

#include <nlohmann/json.hpp>
#include <string>

namespace bounce::python {

/// `value` as JSON. Throws InputError(origin, place) for what JSON cannot hold: NaN or an
/// infinity, an integer beyond 64 bits, a key that is not a string, any other type.
nlohmann::json to_json(pybind11::handle value, const std::string& origin, const std::string& place = "");

/// `j` as plain Python values (dict, list, str, int, float, bool, None).
pybind11::object from_json(const nlohmann::json& j);

/// The Python type's name, for messages ("numpy.ndarray").
std::string type_name(pybind11::handle value);

/// A path argument (a str or an os.PathLike) as text; InputError("python", origin) for anything
/// else (bytes included).
std::string fspath(pybind11::handle value, const std::string& origin);

}  // namespace bounce::python
