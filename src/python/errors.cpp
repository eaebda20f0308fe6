#include "errors.h"

#include "bounce/core/error.h"
#include "bounce/core/progress.h"

namespace py = pybind11;

namespace bounce::python {

namespace {
py::handle error;  // bounce.Error, held for the interpreter's life (the translator raises it)
}  // namespace

void raise_error(const std::string& line) {
    PyErr_SetString(error.ptr(), line.c_str());
    throw py::error_already_set();
}

void add_errors(py::module_& m) {
    error =
        PyErr_NewExceptionWithDoc("bounce.Error",
                                  "Bad input: a scene, mesh, cache, deep file, parameter or argument. str() is the one line the CLI prints "
                                  "(file: place: error: message); .file and .place name them.",
                                  PyExc_ValueError, nullptr);
    static py::handle cancelled = PyErr_NewExceptionWithDoc(
        "bounce.Cancelled", "The render was cancelled (a CancelToken); it left no output.", PyExc_Exception, nullptr);
    m.add_object("Error", error);
    m.add_object("Cancelled", cancelled);
    py::register_exception_translator([](std::exception_ptr p) {
        try {
            if (p) std::rethrow_exception(p);
        } catch (const InputError& e) {
            py::object instance = py::reinterpret_borrow<py::object>(error)(e.what());
            instance.attr("file") = e.file();
            instance.attr("place") = e.place();
            PyErr_SetObject(error.ptr(), instance.ptr());
        } catch (const Cancelled& e) {
            PyErr_SetString(cancelled.ptr(), e.what());
        }
    });
}

}  // namespace bounce::python
