// bounce.Session: the lighting tool's engine (tool/session.h) for scripts and Blender's
// viewport: a scene whose deep buffer and cache stay between renders, so an edit re-renders only
// what it needs (a light's intensity: a re-shade; its position: a re-shade with the bounce light
// stale until a re-gather; geometry or camera: a new deep buffer), as `bounce light` does.
#pragma once

#include <pybind11/pybind11.h>

namespace bounce::python {

void add_session(pybind11::module_& m);

}  // namespace bounce::python
