#include "image.h"

#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <fmt/format.h>

#include "bounce/core/error.h"
#include "convert.h"

namespace py = pybind11;

namespace bounce::python {

namespace {

struct PyImage {
    std::shared_ptr<Image> image;
    py::dict stats;
};

const Layer& layer_of(const PyImage& self, const std::string& name) {
    if (const Layer* l = self.image->find(name)) return *l;
    std::vector<std::string> names;
    for (const Layer& l : self.image->layers) names.push_back(l.name);
    std::string hint = closest_match(name, names);
    throw py::key_error(fmt::format("no layer \"{}\" in this image{} (layers: {})", name,
                                    hint.empty() ? "" : ", did you mean \"" + hint + "\"?", fmt::join(names, ", ")));
}

/// A (height, width, channels) float32 view of `l`; `owner` keeps its buffer alive.
py::array view(const PyImage& self, const Layer& l, py::handle owner) {
    const auto c = static_cast<py::ssize_t>(l.channels.size());
    const auto w = static_cast<py::ssize_t>(self.image->width), h = static_cast<py::ssize_t>(self.image->height);
    const auto f = static_cast<py::ssize_t>(sizeof(float));
    return py::array(py::dtype::of<float>(), {h, w, c}, {w * c * f, c * f, f}, l.data.data(), owner);
}

}  // namespace

py::object wrap_image(std::shared_ptr<Image> image, py::dict stats) { return py::cast(PyImage{std::move(image), std::move(stats)}); }

std::shared_ptr<const Image> image_of(py::handle value, const std::string& call) {
    if (!py::isinstance<PyImage>(value)) throw InputError("python", call, "expects a bounce.Image or the path of an EXR");
    return value.cast<const PyImage&>().image;
}

void add_image(py::module_& m) {
    py::class_<PyImage>(m, "Image", "A rendered window: layers by name as NumPy arrays (height, width, channels), float32, no copy.")
        .def(
            "__getitem__",
            [](py::object self, const std::string& name) {
                const PyImage& i = self.cast<const PyImage&>();
                return view(i, layer_of(i, name), self);
            },
            py::arg("layer"), "The layer as a (height, width, channels) float32 array viewing the image's buffer.")
        .def("__contains__", [](const PyImage& i, const std::string& name) { return i.image->find(name) != nullptr; })
        .def("__len__", [](const PyImage& i) { return i.image->layers.size(); })
        .def("__iter__",
             [](const PyImage& i) {
                 py::list names;
                 for (const Layer& l : i.image->layers) names.append(l.name);
                 return py::iter(names);
             })
        .def_property_readonly(
            "layers",
            [](const PyImage& i) {
                std::vector<std::string> names;
                for (const Layer& l : i.image->layers) names.push_back(l.name);
                return names;
            },
            "The layers' names, in the EXR's order.")
        .def(
            "channels", [](const PyImage& i, const std::string& name) { return layer_of(i, name).channels; }, py::arg("layer"),
            "The layer's EXR channel names (beauty's are R, G, B, A).")
        .def_property_readonly("width", [](const PyImage& i) { return i.image->width; })
        .def_property_readonly("height", [](const PyImage& i) { return i.image->height; })
        .def_property_readonly(
            "window",
            [](const PyImage& i) {
                const Image& w = *i.image;
                return py::make_tuple(w.x0, w.x0 + w.width, w.y0, w.y0 + w.height);
            },
            "(x0, x1, y0, y1) in the full frame, ends exclusive: the crop, or the whole frame.")
        .def_property_readonly("full_size", [](const PyImage& i) { return py::make_tuple(i.image->full_width, i.image->full_height); })
        .def_property_readonly(
            "metadata", [](const PyImage& i) { return i.image->metadata; }, "The EXR's bounce:* attributes.")
        .def_readonly("stats", &PyImage::stats, "The frame's statistics: what `--stats-json` writes.")
        .def(
            "write", [](const PyImage& i, const std::string& path) { write_exr(path, *i.image); }, py::arg("path"),
            "Writes every layer to one OpenEXR, as the CLI does.")
        .def("__repr__", [](const PyImage& i) {
            std::vector<std::string> names;
            for (const Layer& l : i.image->layers) names.push_back(l.name);
            return fmt::format("<bounce.Image {}x{} layers: {}>", i.image->width, i.image->height, fmt::join(names, ", "));
        });
    m.def(
        "read_exr", [](py::handle path) { return wrap_image(std::make_shared<Image>(read_exr(fspath(path, "read_exr()"))), py::dict()); },
        py::arg("path"), "An EXR (a bounce render, or any: channels grouped by their prefix) as a bounce.Image.");
}

}  // namespace bounce::python
