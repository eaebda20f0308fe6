#include "convert.h"

#include <fmt/format.h>

#include <cmath>

#include "bounce/core/error.h"

namespace py = pybind11;

namespace bounce::python {

std::string type_name(py::handle value) {
    const py::handle type = py::type::handle_of(value);
    const std::string module = py::str(type.attr("__module__"));
    const std::string name = py::str(type.attr("__qualname__"));
    return module == "builtins" ? name : module + "." + name;
}

std::string fspath(py::handle value, const std::string& origin) {
    if (!py::isinstance<py::str>(value) && !py::hasattr(value, "__fspath__"))
        throw InputError("python", origin, fmt::format("a path is a str or an os.PathLike, not a {}", type_name(value)));
    py::object p = py::module_::import("os").attr("fspath")(value);
    if (!py::isinstance<py::str>(p)) throw InputError("python", origin, "a path is text, not bytes");
    return p.cast<std::string>();
}

namespace {

nlohmann::json number(py::handle value, const std::string& origin, const std::string& place) {
    if (PyFloat_Check(value.ptr())) {
        const double d = PyFloat_AsDouble(value.ptr());
        if (!std::isfinite(d)) throw InputError(origin, place, fmt::format("{} is not a number a scene file can hold", d));
        return d;
    }
    // Python ints (and NumPy's integers, through __index__) of any size: JSON's are 64-bit.
    py::int_ i = py::reinterpret_steal<py::int_>(PyNumber_Index(value.ptr()));
    if (!i) {  // an object with __index__ that refuses (a NumPy array of several values)
        PyErr_Clear();
        throw InputError(origin, place, fmt::format("a {} is not a value a scene file can hold", type_name(value)));
    }
    int overflow = 0;
    const long long v = PyLong_AsLongLongAndOverflow(i.ptr(), &overflow);
    if (overflow != 0) throw InputError(origin, place, fmt::format("{} is beyond a 64-bit integer", std::string(py::str(i))));
    return static_cast<int64_t>(v);
}

}  // namespace

nlohmann::json to_json(py::handle value, const std::string& origin, const std::string& place) {
    if (value.is_none()) return nullptr;
    if (PyBool_Check(value.ptr())) return value.cast<bool>();
    if (PyFloat_Check(value.ptr()) || PyIndex_Check(value.ptr())) return number(value, origin, place);
    // NumPy's floating scalars that are not Python floats (float32).
    if (py::hasattr(value, "dtype") && py::isinstance(value, py::module_::import("numbers").attr("Real")))
        return number(py::float_(py::reinterpret_borrow<py::object>(value)), origin, place);
    if (PyUnicode_Check(value.ptr())) return value.cast<std::string>();
    if (PyDict_Check(value.ptr())) {
        nlohmann::json out = nlohmann::json::object();
        for (auto [k, v] : py::reinterpret_borrow<py::dict>(value)) {
            if (!PyUnicode_Check(k.ptr()))
                throw InputError(origin, place, fmt::format("a key of type {} (a scene file's keys are strings)", type_name(k)));
            const std::string key = k.cast<std::string>();
            out[key] = to_json(v, origin, place + "/" + key);
        }
        return out;
    }
    if (PyList_Check(value.ptr()) || PyTuple_Check(value.ptr())) {
        nlohmann::json out = nlohmann::json::array();
        size_t n = 0;
        for (py::handle v : py::reinterpret_borrow<py::sequence>(value))
            out.push_back(to_json(v, origin, fmt::format("{}/{}", place, n++)));
        return out;
    }
    throw InputError(origin, place, fmt::format("a {} is not a value a scene file can hold", type_name(value)));
}

py::object from_json(const nlohmann::json& j) {
    switch (j.type()) {
        case nlohmann::json::value_t::null:
            return py::none();
        case nlohmann::json::value_t::boolean:
            return py::bool_(j.get<bool>());
        case nlohmann::json::value_t::number_integer:
            return py::int_(j.get<int64_t>());
        case nlohmann::json::value_t::number_unsigned:
            return py::int_(j.get<uint64_t>());
        case nlohmann::json::value_t::number_float:
            return py::float_(j.get<double>());
        case nlohmann::json::value_t::string:
            return py::str(j.get<std::string>());
        case nlohmann::json::value_t::array: {
            py::list out;
            for (const auto& v : j) out.append(from_json(v));
            return out;
        }
        case nlohmann::json::value_t::object: {
            py::dict out;
            for (const auto& [k, v] : j.items()) out[py::str(k)] = from_json(v);
            return out;
        }
        default:
            return py::none();  // binary and discarded values never come from the library
    }
}

}  // namespace bounce::python
