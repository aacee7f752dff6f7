// The `_sinew` extension module: the compiled half of the `sinew` package (python/sinew/
// __init__.py re-exports it with the pure-Python parts; docs/python.md).
#include "bindings.hpp"

PYBIND11_MODULE(_sinew, m) {
  using namespace sinew::python;
  m.doc() = "sinew's compiled core: models, scenes, runs, simulations and results (see sinew).";
  bind_errors(m);
  bind_model(m);
  bind_scene(m);
  bind_run(m);
  bind_simulation(m);
  bind_results(m);
  bind_fit(m);
}
