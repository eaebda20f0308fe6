// How the library's errors reach Python: InputError (a file, a place, a message: the line the
// CLI prints before exiting with status 2) as bounce.Error, a subclass of ValueError carrying
// .file and .place; a cancelled render as bounce.Cancelled.
#pragma once

#include <pybind11/pybind11.h>

#include <string>

namespace bounce::python {

/// Registers bounce.Error and bounce.Cancelled on `m` and translates the library's exceptions.
void add_errors(pybind11::module_& m);

/// Raises bounce.Error with `line`, a message already in the CLI's form (file: place: error: ...).
[[noreturn]] void raise_error(const std::string& line);

}  // namespace bounce::python
