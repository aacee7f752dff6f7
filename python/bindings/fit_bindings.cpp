// sinew.fit: what sinew-fit does (fit/fit_run.hpp's run_fit), from Python: marker trajectories or
// target shapes → the rig's muscle activations (and the jaw's keys) over time. The options are
// sinew-fit's (FitOptions, docs/fit.md); the result's series come back as NumPy arrays. Like
// sinew.run, the fit works on another thread while this one watches Ctrl-C, which stops its
// runs at a step boundary (the fit then fails, leaving nothing under the output's name).
#include <pybind11/stl.h>

#include "bindings.hpp"
#include "sinew/fit/fit_run.hpp"

namespace sinew::python {
namespace {

py::array_t<double> vector_array(std::vector<double> v) {
  const auto n = static_cast<py::ssize_t>(v.size());
  return take(std::move(v), {n});
}

py::array_t<double> rows_array(const std::vector<std::vector<double>>& rows) {
  const auto r = static_cast<py::ssize_t>(rows.size());
  const auto c = static_cast<py::ssize_t>(rows.empty() ? 0 : rows.front().size());
  std::vector<double> flat;
  flat.reserve(static_cast<std::size_t>(r * c));
  for (const auto& row : rows) flat.insert(flat.end(), row.begin(), row.end());
  return take(std::move(flat), {r, c});
}

py::dict result_dict(const fit::FitResult& f) {
  py::dict d;
  d["output_dir"] = f.output_dir;
  d["muscles"] = f.muscles;
  d["knot_times"] = vector_array(f.knot_times);
  d["activations"] = rows_array(f.activations);
  d["jaw"] = f.jaw;
  d["jaw_values"] = rows_array(f.jaw_values);
  d["frame_times"] = vector_array(f.frame_times);
  d["frame_rms_mm"] = vector_array(f.frame_rms_mm);
  d["frame_max_mm"] = vector_array(f.frame_max_mm);
  d["rms_mm"] = f.rms_mm;
  d["max_mm"] = f.max_mm;
  d["iteration_rms_mm"] = f.iteration_rms_mm;
  d["best_iteration"] = f.best_iteration;
  d["response_runs"] = f.response_runs;
  d["response_runs_reused"] = f.response_runs_reused;
  d["forward_runs"] = f.forward_runs;
  d["steps_per_run"] = f.steps_per_run;
  d["seconds"] = py::dict(py::arg("response") = f.response_s, py::arg("forward") = f.forward_s,
                          py::arg("solve") = f.solve_s, py::arg("total") = f.total_s);
  d["marker_names"] = f.marker_names;
  d["marker_rms_mm"] = vector_array(f.marker_rms_mm);
  d["marker_max_mm"] = vector_array(f.marker_max_mm);
  d["worst_frame"] = f.worst_frame;
  d["worst_frame_residual_mm"] = vector_array(f.worst_frame_residual_mm);
  d["model_path"] = f.model_path;
  d["surface"] = f.surface;
  return d;
}

}  // namespace

void bind_fit(py::module_& m) {
  py::class_<fit::FitOptions>(m, "_FitOptions")
      .def(py::init<>())
      .def_readwrite("scene_path", &fit::FitOptions::scene_path)
      .def_readwrite("markers_path", &fit::FitOptions::markers_path)
      .def_readwrite("targets_path", &fit::FitOptions::targets_path)
      .def_readwrite("target_surface", &fit::FitOptions::target_surface)
      .def_readwrite("target_markers", &fit::FitOptions::target_markers)
      .def_readwrite("output_dir", &fit::FitOptions::output_dir)
      .def_readwrite("muscles", &fit::FitOptions::muscles)
      .def_readwrite("jaw", &fit::FitOptions::jaw)
      .def_readwrite("max_activation", &fit::FitOptions::max_activation)
      .def_readwrite("knot_interval", &fit::FitOptions::knot_interval)
      .def_readwrite("step_activation", &fit::FitOptions::step_activation)
      .def_readwrite("response_ramp", &fit::FitOptions::response_ramp)
      .def_readwrite("smoothing", &fit::FitOptions::smoothing)
      .def_readwrite("effort", &fit::FitOptions::effort)
      .def_readwrite("corrections", &fit::FitOptions::corrections)
      .def_readwrite("marker_unit", &fit::FitOptions::marker_unit)
      .def_readwrite("sample_interval", &fit::FitOptions::sample_interval)
      .def_readwrite("cache_dir", &fit::FitOptions::cache_dir)
      .def_readwrite("device", &fit::FitOptions::device)
      .def_readwrite("threads", &fit::FitOptions::threads);
  m.def(
      "_fit",
      [](const fit::FitOptions& options) {
        const auto result = run_watching_signals([options] { return fit::run_fit(options); });
        return result_dict(result);
      },
      py::arg("options"));
}

}  // namespace sinew::python
