#include "arguments.h"

#include <fmt/format.h>

#include <cmath>

#include "bounce/core/error.h"
#include "convert.h"

namespace py = pybind11;

namespace bounce::python {

Arguments::Arguments(std::string call, const py::args& args, const py::kwargs& kwargs) : call_(std::move(call)) {
    if (!args.empty())
        throw InputError("python", call_ + "()", fmt::format("takes keyword arguments only ({} given by position)", args.size()));
    given_ = py::dict(kwargs);
}

void Arguments::fail(const std::string& name, py::handle value, const std::string& message) const {
    throw InputError("python", fmt::format("{}({}={})", call_, name, py::repr(value).cast<std::string>()), message);
}

py::object Arguments::take(const char* name) {
    taken_.insert(name);
    return given_.contains(name) ? py::object(given_[name]) : py::none();
}

std::string Arguments::path(const char* name) {
    py::object v = take(name);
    if (v.is_none()) return "";
    const std::string s = fspath(v, fmt::format("{}({}={})", call_, name, py::repr(v).cast<std::string>()));
    if (s.empty()) fail(name, v, "an empty path (leave the argument out instead)");
    if (s.find('\0') != std::string::npos) fail(name, v, "a path holds no NUL character");
    return s;
}

bool Arguments::flag(const char* name) {
    py::object v = take(name);
    if (v.is_none()) return false;
    if (!PyBool_Check(v.ptr())) fail(name, v, fmt::format("expects True or False, not a {}", type_name(v)));
    return v.cast<bool>();
}

std::string Arguments::text(const char* name, const std::string& fallback) {
    py::object v = take(name);
    if (v.is_none()) return fallback;
    if (!py::isinstance<py::str>(v)) fail(name, v, fmt::format("expects a str, not a {}", type_name(v)));
    return v.cast<std::string>();
}

std::optional<double> Arguments::number(const char* name) {
    py::object v = take(name);
    if (v.is_none()) return std::nullopt;
    if (PyBool_Check(v.ptr()) || !(PyFloat_Check(v.ptr()) || PyIndex_Check(v.ptr()) || py::hasattr(v, "__float__")))
        fail(name, v, fmt::format("expects a number, not a {}", type_name(v)));
    const double d = py::float_(v).cast<double>();
    if (!std::isfinite(d)) fail(name, v, "expects a finite number");
    return d;
}

py::object Arguments::callable(const char* name) {
    py::object v = take(name);
    if (!v.is_none() && !PyCallable_Check(v.ptr())) fail(name, v, fmt::format("expects a callable, not a {}", type_name(v)));
    return v;
}

std::vector<std::pair<std::string, py::object>> Arguments::rest() const {
    std::vector<std::pair<std::string, py::object>> out;
    for (auto [k, v] : given_) {
        const std::string key = k.cast<std::string>();
        if (!taken_.count(key)) out.emplace_back(key, py::reinterpret_borrow<py::object>(v));
    }
    return out;
}

}  // namespace bounce::python
