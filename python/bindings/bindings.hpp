#pragma once
// The pieces of the `_sinew` extension module (module.cpp puts them together): each bind_* adds
// one concern's classes and functions, and the helpers here turn C++ vectors into NumPy arrays.
//
// Arrays: `take` hands a vector's memory to NumPy without a copy (the array owns it; writable);
// `view` shows memory another Python object owns (a Model's datasets) read-only, kept alive by
// that object (the array's base).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <chrono>
#include <future>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "sinew/formats/model.hpp"
#include "sinew/simulator/run/runner.hpp"
#include "sinew/simulator/run/scene.hpp"

namespace sinew::python {

namespace py = pybind11;

void bind_errors(py::module_& m);
void bind_model(py::module_& m);
void bind_scene(py::module_& m);
void bind_run(py::module_& m);
void bind_simulation(py::module_& m);
void bind_results(py::module_& m);
void bind_fit(py::module_& m);

// sinew.Model: a model in memory (read, voxelized or a simulation's), immutable, with the file it
// came from or was saved to ("" when it has none).
struct PyModel {
  std::shared_ptr<const formats::Model> model;
  std::string path;
  std::string voxelize_summary;  // sinew-voxelize --json's summary when voxelize() made it
};

// sinew.Scene: a scene's text, validated (parse_scene_text), with the file it came from ("" for
// one made in memory) and the folder its relative model path resolves against.
struct PyScene {
  std::string text;
  std::string file;
  std::string directory;
  simulator::Scene scene;
};
// The name a scene has in messages: its file, or "scene (from a dict)".
std::string scene_name(const PyScene& scene);
// The precision named "float" or "double" (None: the scene's); ConfigError otherwise.
std::optional<simulator::Precision> precision_from(const py::object& name);

// Runs `work` with the GIL released and sinew's exceptions kept (translated once back under the
// GIL by the registered translator).
template <typename F>
auto without_gil(F&& work) {
  py::gil_scoped_release release;
  return work();
}

// Runs `work` (a run_scene, a fit) on another thread while this one holds on to Python's signals:
// Python keeps SIGINT, so this thread waits with the GIL released and checks Python's signals
// every 50 ms; on KeyboardInterrupt it asks the runs to stop (simulator::request_interrupt: at
// their next step boundary, with a checkpoint, as the tools' SIGINT), waits for `work` to end and
// raises KeyboardInterrupt. `work`'s own exception is rethrown otherwise.
template <typename F>
auto run_watching_signals(F work) -> decltype(work()) {
  using Result = decltype(work());
  simulator::clear_interrupt();
  std::packaged_task<Result()> task(std::move(work));
  auto result = task.get_future();
  std::thread worker(std::move(task));
  bool interrupted = false;
  {
    py::gil_scoped_release release;
    while (result.wait_for(std::chrono::milliseconds(50)) != std::future_status::ready) {
      py::gil_scoped_acquire acquire;
      if (!interrupted && PyErr_CheckSignals() != 0) {
        interrupted = true;
        PyErr_Clear();  // raised again below, once the work has stopped
        simulator::request_interrupt();
      }
    }
  }
  worker.join();
  simulator::clear_interrupt();
  if (interrupted) {
    try {
      result.get();
    } catch (...) {
      // The interruption is what the caller asked for; the work's failure follows from it.
    }
    PyErr_SetNone(PyExc_KeyboardInterrupt);
    throw py::error_already_set();
  }
  return result.get();  // rethrows the work's exception (translated to sinew.*)
}

// A vector's memory as a NumPy array of `shape` (the array owns it; no copy).
template <typename T>
py::array_t<T> take(std::vector<T>&& values, std::vector<py::ssize_t> shape) {
  auto* heap = new std::vector<T>(std::move(values));
  py::capsule owner(heap, [](void* p) { delete static_cast<std::vector<T>*>(p); });
  return py::array_t<T>(std::move(shape), heap->data(), owner);
}

// Memory owned by `base` as a read-only NumPy array of `shape` (C order).
template <typename T>
py::array_t<T> view(const T* data, std::vector<py::ssize_t> shape, py::handle base) {
  py::array_t<T> a = data ? py::array_t<T>(std::move(shape), data, base)
                          : py::array_t<T>(std::move(shape));  // empty: nothing to share
  a.attr("setflags")(py::arg("write") = false);
  return a;
}

// A contiguous C-order float64 copy of an array-like with `cols` columns (0: one dimension);
// throws sinew::ConfigError naming `what` for a wrong shape or a value that is not finite.
std::vector<double> finite_doubles(const py::handle& values, const std::string& what,
                                   py::ssize_t cols);
// The node ids in an array-like of integers (one dimension), as sinew's 32-bit ids; throws
// ConfigError naming `what` for a wrong shape or an id outside [0, count).
std::vector<std::int32_t> node_ids(const py::handle& values, const std::string& what,
                                   std::size_t count);

}  // namespace sinew::python
