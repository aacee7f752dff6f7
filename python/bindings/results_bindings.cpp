// The compiled half of sinew.Results (python/sinew/_results.py): a results file's datasets as NumPy
// arrays through the one HDF5 layer (formats/hdf5_file.hpp: its checks, its lock, its messages),
// the visual surfaces through postprocess's reader, and sinew-export's writers.
#include <pybind11/stl.h>

#include "bindings.hpp"
#include "sinew/common/error.hpp"
#include "sinew/formats/hdf5_file.hpp"
#include "sinew/postprocess/export_results.hpp"
#include "sinew/postprocess/results_file.hpp"
#include "sinew/postprocess/results_reader.hpp"

namespace sinew::python {
namespace {

namespace h5 = formats::hdf5;

std::vector<py::ssize_t> to_shape(const std::vector<hsize_t>& dims) {
  std::vector<py::ssize_t> shape;
  for (const auto d : dims) shape.push_back(static_cast<py::ssize_t>(d));
  return shape;
}

// A whole dataset with its shape: integers as int64, everything else as float64.
py::array read_dataset(const std::string& path, const std::string& name, bool integers) {
  std::vector<py::ssize_t> shape;
  std::vector<std::int64_t> ints;
  std::vector<double> reals;
  without_gil([&] {
    const auto file = postprocess::open_results(path);
    if (!h5::exists(file.get(), name))
      throw FormatError(path, name, "missing dataset (docs/results-format.md)");
    shape = to_shape(h5::shape(file.get(), name, path));
    if (integers) {
      ints = h5::read<std::int64_t>(file.get(), name, path);
    } else {
      reals = h5::read<double>(file.get(), name, path);
    }
  });
  if (integers) return take(std::move(ints), std::move(shape));
  return take(std::move(reals), std::move(shape));
}

}  // namespace

void bind_results(py::module_& m) {
  m.def(
      "_results_check", [](const std::string& path) { postprocess::open_results(path); },
      py::arg("path"));
  m.def("_results_dataset", &read_dataset, py::arg("path"), py::arg("name"),
        py::arg("integers") = false);
  m.def(
      "_results_has",
      [](const std::string& path, const std::string& name) {
        const auto file = postprocess::open_results(path);
        return h5::exists(file.get(), name);
      },
      py::arg("path"), py::arg("name"));
  m.def("_results_surfaces", &postprocess::list_surfaces, py::arg("path"));
  m.def(
      "_results_skin",
      [](const std::string& path, const std::string& surface, std::int64_t frame) {
        auto anim = without_gil([&] { return postprocess::read_surface(path, surface); });
        const auto frames = static_cast<std::int64_t>(anim.frame_count());
        const std::int64_t f = frame < 0 ? frames + frame : frame;
        if (f < 0 || f >= frames)
          throw ConfigError(path, "frame",
                            "frame " + std::to_string(frame) + " out of range (the file has " +
                                std::to_string(frames) + " frames)");
        const auto v = static_cast<py::ssize_t>(anim.vertex_count());
        const auto t = static_cast<py::ssize_t>(anim.triangle_count());
        return py::make_tuple(anim.name, take(std::move(anim.frames[f]), {v, 3}),
                              take(std::move(anim.triangles), {t, 3}));
      },
      py::arg("path"), py::arg("surface"), py::arg("frame"));
  m.def(
      "_export",
      [](const std::string& results, const std::string& surface, const std::string& glb,
         const std::string& pc2, const std::string& rest_obj, const std::string& obj_sequence,
         const std::string& up, const std::string& color, double fps, double time_scale,
         bool linear) {
        postprocess::ExportRequest r{results, surface, glb, pc2,        rest_obj, obj_sequence,
                                     up,      color,   fps, time_scale, linear};
        return without_gil([&] { return postprocess::export_results(r); });
      },
      py::arg("results"), py::arg("surface"), py::arg("glb"), py::arg("pc2"), py::arg("rest_obj"),
      py::arg("obj_sequence"), py::arg("up"), py::arg("color"), py::arg("fps"),
      py::arg("time_scale"), py::arg("linear"));
}

}  // namespace sinew::python
