// bounce.compare, bounce.params and the cache tools (bounce.cache_info, cache_merge,
// cache_filter, cache_export; the package's bounce.cache module names them info, merge, filter,
// export): `bounce compare --json`, `bounce params --json` and `bounce cache ...` as Python
// calls returning dicts.
#pragma once

#include <pybind11/pybind11.h>

namespace bounce::python {

void add_tools(pybind11::module_& m);

}  // namespace bounce::python
