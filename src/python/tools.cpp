#include "tools.h"

#include <pybind11/stl.h>

#include <fmt/format.h>

#include <cmath>
#include <filesystem>

#include "arguments.h"
#include "bounce/cache/cache_file.h"
#include "bounce/cache/cache_tools.h"
#include "bounce/config/params.h"
#include "bounce/core/error.h"
#include "bounce/core/image_compare.h"
#include "convert.h"
#include "image.h"

namespace py = pybind11;

namespace bounce::python {

namespace {

ToolCall python_call(const char* command, const std::string& output) {
    return {"python", fmt::format("{}(output=\"{}\")", command, output), std::string(command) + "()"};
}

py::object counts(const CacheFile& f) {
    return from_json({{"records", f.records.size()}, {"fragment_records", f.fragment_records.size()}});
}

/// An image argument: a bounce.Image, or the path of an EXR (read here).
std::shared_ptr<const Image> image_arg(Arguments& a, const char* name, std::string& label) {
    py::object v = a.take(name);
    if (v.is_none()) throw InputError("python", a.call() + "()", fmt::format("give {}", name));
    if (py::isinstance<py::str>(v) || py::hasattr(v, "__fspath__")) {
        label = fspath(v, fmt::format("{}({}=...)", a.call(), name));
        return std::make_shared<const Image>(read_exr(label));
    }
    label = name;
    return image_of(v, fmt::format("{}({}=...)", a.call(), name));
}

/// floats of a box (6) or a sphere (4); InputError naming the argument otherwise.
std::vector<float> floats(Arguments& a, const char* name, size_t n) {
    py::object v = a.take(name);
    if (v.is_none()) return {};
    std::vector<float> out;
    if (py::isinstance<py::sequence>(v) && !py::isinstance<py::str>(v))
        for (py::handle x : py::reinterpret_borrow<py::sequence>(v)) {
            if (PyBool_Check(x.ptr()) || !(PyFloat_Check(x.ptr()) || PyIndex_Check(x.ptr()))) break;
            const double d = py::float_(py::reinterpret_borrow<py::object>(x)).cast<double>();
            if (!std::isfinite(d) || std::fabs(d) > 3.4e38) a.fail(name, v, "its numbers must be finite floats");
            out.push_back(static_cast<float>(d));
        }
    if (out.size() != n || py::len(v) != n) a.fail(name, v, fmt::format("expects {} numbers", n));
    return out;
}

RecordFilter filter_of(Arguments& a) {
    RecordFilter filter;
    if (auto v = floats(a, "box", 6); !v.empty()) {
        filter.has_box = true;
        filter.box_lo = {std::min(v[0], v[3]), std::min(v[1], v[4]), std::min(v[2], v[5])};
        filter.box_hi = {std::max(v[0], v[3]), std::max(v[1], v[4]), std::max(v[2], v[5])};
    }
    if (auto v = floats(a, "sphere", 4); !v.empty()) {
        filter.has_sphere = true;
        filter.center = {v[0], v[1], v[2]};
        filter.radius = v[3];
        if (!(filter.radius > 0)) throw InputError("python", "filter(sphere=...)", "the radius must be > 0");
    }
    py::object where = a.take("where");
    if (py::isinstance<py::str>(where)) where = py::make_tuple(where);
    if (!where.is_none()) {
        if (!py::isinstance<py::sequence>(where)) a.fail("where", where, "expects a term (\"radius < 0.1\") or a list of them");
        for (py::handle t : py::reinterpret_borrow<py::sequence>(where)) {
            if (!py::isinstance<py::str>(t)) a.fail("where", where, "its terms are text, as \"radius < 0.1\"");
            filter.where.push_back(WhereTerm::parse(t.cast<std::string>()));
        }
    }
    return filter;
}

template <typename F>
auto keywords(const char* call, F&& body) {
    return [call, body](const py::args& args, const py::kwargs& kwargs) {
        Arguments a(call, args, kwargs);
        py::object out = body(a);
        if (const auto rest = a.rest(); !rest.empty()) a.fail(rest.front().first, rest.front().second, "is not an argument of this call");
        return out;
    };
}

}  // namespace

void add_tools(py::module_& m) {
    m.def(
        "params", [] { return from_json(params_listing()); },
        "Every parameter of the table: key, stage, type, default, range, unit, doc, flag (`bounce params --json`).");
    m.def("compare",
          keywords("compare",
                   [](Arguments& a) {
                       std::string test_name, ref_name;
                       const auto test = image_arg(a, "test", test_name);
                       const auto ref = image_arg(a, "reference", ref_name);
                       const std::string layer = a.text("layer", "");
                       return from_json(layer_errors_json(compare_images(*test, *ref, layer, test_name, ref_name)));
                   }),
          "compare(test=, reference=, layer=None): per layer rmse, rel_rmse, relmse, mean_abs, max_abs, mean_ref "
          "(`bounce compare --json`); test and reference are bounce.Images or EXR paths.");
    m.def("cache_info",
          keywords("cache_info",
                   [](Arguments& a) {
                       const std::string path = a.path("path");
                       if (path.empty()) throw InputError("python", "cache_info()", "give path");
                       const CacheFile file = read_cache_file(path);  // first: it names a file that is not there
                       return from_json(cache_info(file, std::filesystem::file_size(path)));
                   }),
          "cache_info(path=): counts, bounds, parameters, radius histogram, memory (`bounce cache info --json`).");
    m.def("cache_merge",
          keywords("merge",
                   [](Arguments& a) {
                       py::object inputs = a.take("inputs");
                       std::vector<std::string> paths;
                       if (!py::isinstance<py::sequence>(inputs) || py::isinstance<py::str>(inputs))
                           a.fail("inputs", inputs, "expects a list of cache files");
                       for (py::handle p : py::reinterpret_borrow<py::sequence>(inputs)) paths.push_back(fspath(p, "merge(inputs=[...])"));
                       const std::string output = a.path("output");
                       const bool force = a.flag("force");
                       return counts(merge_cache_files(python_call("merge", output), paths, output, force));
                   }),
          "cache_merge(inputs=[...], output=, force=False): the caches merged without duplicates into output (.bic).");
    m.def("cache_filter",
          keywords("filter",
                   [](Arguments& a) {
                       const std::string input = a.path("input"), output = a.path("output");
                       const bool remove = a.flag("remove");
                       const RecordFilter filter = filter_of(a);
                       return counts(filter_cache_file(python_call("filter", output), input, output, filter, remove).second);
                   }),
          "cache_filter(input=, output=, box=(x0,y0,z0,x1,y1,z1), sphere=(x,y,z,r), where=[\"radius < 0.1\"], remove=False).");
    m.def("cache_export",
          keywords("export",
                   [](Arguments& a) {
                       const std::string input = a.path("input"), output = a.path("output");
                       check_tool_output(python_call("export", output), output, ".ply", "the exported point cloud", {input});
                       const CacheFile f = read_cache_file(input);
                       export_ply(f, output);
                       return counts(f);
                   }),
          "cache_export(input=, output=): a PLY point cloud of the records.");
}

}  // namespace bounce::python
